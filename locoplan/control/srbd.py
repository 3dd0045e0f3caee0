"""Single-rigid-body dynamics (SRBD) of the paper, linearised, with its exact discretisation.

State x (15,) = [Theta (roll, pitch, yaw; rad); p_c (CoM, world; m); omega (angular velocity,
WORLD frame; rad/s); pdot_c (CoM velocity, world; m/s); g (gravity, [0, 0, -9.81] m/s^2)].
Gravity is carried as a state so that the dynamics stay linear (no affine gravity term).

Inputs u (10,) in the paper's order [F1; F2; M1; M2]: F_i (3,) the contact force of foot i in
the world frame (N), M_i = [M_iy, M_iz] (2,) the line-foot moment in foot i's yaw frame (N m),
acting in the world as R_z(psi_foot_i) L M_i with L = [[0, 0], [1, 0], [0, 1]] (no moment
about the foot's long x axis).

Continuous model, linearised about the reference yaw psi with small roll and pitch::

    Theta_dot = R_z(psi)^T omega
    p_dot     = pdot_c
    omega_dot = I_world^-1 (sum_i sigma_i (r_i x F_i + R_z(psi_i) L M_i) + sigma_e r_e x F_ext)
    pdot_dot  = sum_i sigma_i F_i / m + sigma_e F_ext / m + g

with r_i = p_foot_i - p_c, r_e = p_object - p_c, I_world = R_z(psi) I_body R_z(psi)^T (the
gyroscopic term omega x I omega is dropped, as in the paper and MIT's convex MPC).

Why Theta_dot = R_z(psi)^T omega: the paper's R_b maps ZYX Euler rates to the world angular
velocity, omega = R_b Theta_dot, and equals R_z(psi) at zero pitch; the dynamics need the
inverse, Theta_dot = R_b^-1 omega, whose small-roll/pitch value is R_z(psi)^T (the choice of
MIT's convex MPC). Putting R_b itself in A, as the paper's equation reads, would rotate the
wrong way whenever the yaw is not zero.

Model 2 (external force, the paper's choice): a held object of mass m_o enters as the known
force F_ext = [0, 0, -m_o 9.81] at p_object, an affine term d. Model 1 (combined rigid body):
while held, the robot and object form one body of mass m + m_o whose moments are taken about
the combined CoM p_h = (m p_c + m_o p_o) / (m + m_o), with the parallel-axis inertia; no
F_ext. The state keeps describing the robot (the object is rigidly held, so p_c and p_h share
their acceleration).

Discretisation: zero-order hold, exp([[A, B, d], [0, 0, 0]] dt). A is nilpotent here: A^2 has
only the block p <- g (= I) and A^3 = 0, A^2 B = 0 and A^2 d = 0 because B and d have no
rows on g. The augmented matrix M therefore has M^3 = 0 and the exponential is exactly
I + M dt + M^2 dt^2 / 2, i.e. A_d = I + A dt + A^2 dt^2/2, B_d = B dt + A B dt^2/2,
d_d = d dt + A d dt^2/2.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np
import numpy.typing as npt
import scipy.linalg

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

GRAVITY: Final[float] = 9.81
"""Gravitational acceleration (m/s^2); the gravity state is [0, 0, -GRAVITY]."""
NX: Final[int] = 15
"""State dimension."""
NU: Final[int] = 10
"""Input dimension [F1; F2; M1; M2]."""

# State slices.
THETA: Final = slice(0, 3)
POS: Final = slice(3, 6)
OMEGA: Final = slice(6, 9)
VEL: Final = slice(9, 12)
GRAV: Final = slice(12, 15)

L_SELECT: Final[FloatArray] = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
"""The paper's moment selection L (3, 2): line-foot moments about the foot's y and z axes."""


def gravity_state() -> FloatArray:
    """The gravity part of the state, [0, 0, -9.81] (m/s^2)."""
    return np.array([0.0, 0.0, -GRAVITY])


def rot_z(psi: float) -> FloatArray:
    """Rotation (3, 3) about world z by psi (rad)."""
    c, s = np.cos(psi), np.sin(psi)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def skew(v: FloatArray) -> FloatArray:
    """Skew matrix (3, 3) with skew(v) @ w = v x w."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def inertia_world(inertia_body: FloatArray, yaw: float) -> FloatArray:
    """Body inertia (3, 3) (kg m^2, body axes) expressed in the world at yaw (rad)."""
    R = rot_z(yaw)
    return R @ inertia_body @ R.T


def point_mass_inertia(mass: float, offset: FloatArray) -> FloatArray:
    """Inertia (3, 3) of a point mass (kg) at offset (3,) (m): m (|d|^2 I - d d^T)."""
    return mass * (float(offset @ offset) * np.eye(3) - np.outer(offset, offset))


@dataclass(frozen=True, slots=True)
class CombinedBody:
    """Model 1's rigid body: robot plus held object.

    ``mass`` (kg), ``p_com_world`` (3,) the combined CoM p_h (m), ``inertia_world`` (3, 3)
    about p_h in world axes (kg m^2).
    """

    mass: float
    p_com_world: FloatArray
    inertia_world: FloatArray


def combined_body(
    mass: float,
    inertia_world_robot: FloatArray,
    p_com_world: FloatArray,
    object_mass: float,
    p_object_world: FloatArray,
    object_inertia_world: FloatArray | None = None,
) -> CombinedBody:
    """Combine the robot's SRB with a held object by the parallel-axis theorem (Model 1).

    The object is a point mass at ``p_object_world`` plus, if given, its own inertia
    (3, 3) about its CoM in world axes. Masses kg, positions m (3,).
    """
    m_total = mass + object_mass
    p_h = (mass * p_com_world + object_mass * p_object_world) / m_total
    inertia = (
        inertia_world_robot
        + point_mass_inertia(mass, p_com_world - p_h)
        + point_mass_inertia(object_mass, p_object_world - p_h)
    )
    if object_inertia_world is not None:
        inertia = inertia + object_inertia_world
    return CombinedBody(mass=m_total, p_com_world=p_h, inertia_world=inertia)


@dataclass(frozen=True, slots=True)
class ContinuousModel:
    """Continuous SRBD at one step: x_dot = A x + B u + d. A (15, 15), B (15, 10), d (15,)."""

    A: FloatArray
    B: FloatArray
    d: FloatArray


@dataclass(frozen=True, slots=True)
class DiscreteModel:
    """Discrete SRBD at one step: x+ = A x + B u + d. A (15, 15), B (15, 10), d (15,)."""

    A: FloatArray
    B: FloatArray
    d: FloatArray


def continuous_model(
    yaw: float,
    p_com_world: FloatArray,
    p_feet_world: FloatArray,
    foot_yaw: FloatArray,
    contact: BoolArray,
    mass: float,
    inertia_body: FloatArray,
    object_held: bool = False,
    object_mass: float = 0.0,
    p_object_world: FloatArray | None = None,
    model: str = "external-force",
) -> ContinuousModel:
    """Continuous A, B, d of the SRBD linearised at one step.

    yaw (rad): the reference yaw to linearise about. p_com_world (3,): the CoM position used
    for the lever arms (m). p_feet_world (2, 3), foot_yaw (2,) (rad), contact (2,) bool (the
    sigma_Ci). mass (kg), inertia_body (3, 3) (kg m^2, body axes). object_held (sigma_e),
    object_mass (kg), p_object_world (3,). model: "external-force" (Model 2) or "combined"
    (Model 1). Swing feet give zero columns in B.
    """
    if model not in ("external-force", "combined"):
        raise ValueError(f"unknown SRBD model {model!r}")
    Rz = rot_z(yaw)
    I_w = inertia_world(inertia_body, yaw)
    m = mass
    p_ref = np.asarray(p_com_world, dtype=np.float64)
    F_ext = np.zeros(3)
    r_e = np.zeros(3)
    held = object_held and object_mass > 0.0
    if held:
        if p_object_world is None:
            raise ValueError("p_object_world is needed while an object is held")
        if model == "combined":
            body = combined_body(m, I_w, p_ref, object_mass, p_object_world)
            m, I_w, p_ref = body.mass, body.inertia_world, body.p_com_world
        else:
            F_ext = np.array([0.0, 0.0, -object_mass * GRAVITY])
            r_e = p_object_world - p_ref
    I_inv = np.linalg.inv(I_w)

    A = np.zeros((NX, NX))
    A[THETA, OMEGA] = Rz.T
    A[POS, VEL] = np.eye(3)
    A[VEL, GRAV] = np.eye(3)

    B = np.zeros((NX, NU))
    for i in range(2):
        if not contact[i]:
            continue
        r = p_feet_world[i] - p_ref
        R_f = rot_z(float(foot_yaw[i]))
        B[OMEGA, 3 * i : 3 * i + 3] = I_inv @ skew(r)
        B[OMEGA, 6 + 2 * i : 8 + 2 * i] = I_inv @ R_f @ L_SELECT
        B[VEL, 3 * i : 3 * i + 3] = np.eye(3) / m

    d = np.zeros(NX)
    if held and model == "external-force":
        d[OMEGA] = I_inv @ np.cross(r_e, F_ext)
        d[VEL] = F_ext / m
    return ContinuousModel(A=A, B=B, d=d)


def discretize(cm: ContinuousModel, dt: float) -> DiscreteModel:
    """Exact zero-order-hold discretisation using A^3 = 0, A^2 B = 0, A^2 d = 0 (see module).

    Raises ValueError if the model does not have that structure (checked, cheap).
    """
    A, B, d = cm.A, cm.B, cm.d
    A2 = A @ A
    if np.any(A2 @ A) or np.any(A2 @ B) or np.any(A2 @ d):
        raise ValueError("discretize: the model is not nilpotent of the SRBD structure")
    Ad = np.eye(A.shape[0]) + A * dt + A2 * (dt * dt / 2.0)
    Bd = B * dt + (A @ B) * (dt * dt / 2.0)
    dd = d * dt + (A @ d) * (dt * dt / 2.0)
    return DiscreteModel(A=Ad, B=Bd, d=dd)


def discretize_expm(cm: ContinuousModel, dt: float) -> DiscreteModel:
    """Reference zero-order hold through scipy.linalg.expm of the augmented matrix (slow)."""
    n, m = cm.B.shape
    M = np.zeros((n + m + 1, n + m + 1))
    M[:n, :n] = cm.A
    M[:n, n : n + m] = cm.B
    M[:n, n + m] = cm.d
    E = scipy.linalg.expm(M * dt)
    return DiscreteModel(A=E[:n, :n], B=E[:n, n : n + m], d=E[:n, n + m])


def input_vector(forces_world: FloatArray, moments_foot: FloatArray) -> FloatArray:
    """u (10,) = [F1; F2; M1; M2] from forces_world (2, 3) (N) and moments_foot (2, 2) (N m)."""
    return np.concatenate([forces_world[0], forces_world[1], moments_foot[0], moments_foot[1]])


def rollout(models: list[DiscreteModel], x0: FloatArray, u: FloatArray) -> FloatArray:
    """States x_1..x_N (N, 15) from x0 (15,) and inputs u (N, 10), one model per step."""
    X = np.empty((len(models), x0.shape[0]))
    x = x0
    for k, dm in enumerate(models):
        x = dm.A @ x + dm.B @ u[k] + dm.d
        X[k] = x
    return X


def rk4_rollout(
    cm: ContinuousModel, x0: FloatArray, u: FloatArray, dt: float, substeps: int
) -> FloatArray:
    """x(dt) of x_dot = A x + B u + d under constant u by ``substeps`` classical RK4 steps."""
    h = dt / substeps

    def f(x: FloatArray) -> FloatArray:
        return np.asarray(cm.A @ x + cm.B @ u + cm.d)

    x = np.array(x0, dtype=np.float64)
    for _ in range(substeps):
        k1 = f(x)
        k2 = f(x + 0.5 * h * k1)
        k3 = f(x + 0.5 * h * k2)
        k4 = f(x + h * k3)
        x = x + (h / 6.0) * (k1 + 2 * k2 + 2 * k3 + k4)
    return x
