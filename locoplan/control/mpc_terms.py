"""Structured pieces of the condensed multi-contact MPC (see `mpc`): pure functions on arrays.

The SRBD's A is nilpotent, so every block of the condensed prediction matrix is an affine
function of the step distance. The Hessian is therefore assembled from per-step features
Phi_k (6 x 10: the omega and pdot kicks of step k's ten foot-frame wrench components) and a
per-step-pair kernel K[k, l] (6 x 6) that depends only on the linearisation yaws:
H[k, l] = Phi_k' K[k, l] Phi_l + R. With Q diagonal there are no cross terms between the
(Theta, omega) and (p, pdot) groups:

    K_omega[k, l] = cnt Q_omega + dt^2 sum_{i >= m} (C_i - E_k)' Q_Theta (C_i - E_l)
    K_pdot[k, l]  = cnt Q_pdot  + dt^2 sum_{i >= m} (i - k + 1/2)(i - l + 1/2) Q_p

with m = max(k, l), cnt = N - m, C_i = sum_{j <= i} R_z(yaw_j)', E_k = C_k - R_z(yaw_k)'/2.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from locoplan.control import srbd

if TYPE_CHECKING:
    from locoplan.control.mpc import MpcInput, MpcSettings

FloatArray = npt.NDArray[np.float64]


def rot_z_stack(yaw: FloatArray) -> FloatArray:
    """Rotations about z, shape yaw.shape + (3, 3)."""
    c, s = np.cos(yaw), np.sin(yaw)
    R = np.zeros((*yaw.shape, 3, 3))
    R[..., 0, 0] = c
    R[..., 0, 1] = -s
    R[..., 1, 0] = s
    R[..., 1, 1] = c
    R[..., 2, 2] = 1.0
    return R


def suffix_sum(a: FloatArray) -> FloatArray:
    """s_k = sum_{i >= k} a_i along axis 0."""
    return np.cumsum(a[::-1], axis=0)[::-1]


@dataclass(frozen=True, slots=True)
class Kernel:
    """Cached per (N, dt, Q, yaw_lin): the step-pair kernel and gradient helpers.

    ``K_cols`` (N, 6N, 6): column block l of the (6N, 6N) matrix of blocks K[k, l].
    ``C`` (N, 3, 3): C_i = sum_{j <= i} R_z(yaw_j)^T; ``E`` (N, 3, 3): C_k - R_z(yaw_k)^T / 2,
    so that the pitch/roll/yaw response of x_{i+1} to step k's omega kick is
    dt (C_i - E_k) (i >= k). ``RzT`` (N, 3, 3). ``Iinv`` (N, 3, 3) the trunk's inverse world
    inertia R_z I_body^-1 R_z^T (also keyed on I_body).
    """

    K_cols: FloatArray
    C: FloatArray
    E: FloatArray
    CT: FloatArray
    ET: FloatArray
    RzT: FloatArray
    Iinv: FloatArray


def build_kernel(
    N: int, dt: float, q: FloatArray, yaw_lin: FloatArray, Ib_inv: FloatArray
) -> Kernel:
    q_th, q_p, q_w, q_v = q[0:3], q[3:6], q[6:9], q[9:12]
    RzT = np.swapaxes(rot_z_stack(yaw_lin), -1, -2)
    C = np.cumsum(RzT, axis=0)
    E = C - 0.5 * RzT
    idx = np.arange(N)
    mx = np.maximum.outer(idx, idx)  # max(k, l)
    cnt = (N - mx).astype(np.float64)  # number of i with i >= max(k, l)
    # Sp[k, l] = sum_{i >= max(k,l)} (i - k + 1/2)(i - l + 1/2)
    i = idx[:, None, None]
    terms = np.where(
        i >= mx[None], (i - idx[None, :, None] + 0.5) * (i - idx[None, None, :] + 0.5), 0.0
    )
    Sp = terms.sum(axis=0)
    # Theta kernel: T[k, l] = sum_{i >= m} (C_i - E_k)' Q (C_i - E_l), m = max(k, l).
    QC = q_th[None, :, None] * C  # Q C_i
    S1 = suffix_sum(QC)  # sum_{i >= m} Q C_i
    S2 = suffix_sum(np.swapaxes(C, 1, 2) @ QC)  # sum_{i >= m} C_i' Q C_i
    S1m = S1[mx]  # (N, N, 3, 3)
    ET = np.swapaxes(E, 1, 2)
    T = (
        S2[mx]
        - ET[:, None] @ S1m
        - np.swapaxes(S1m, -1, -2) @ E[None, :]
        + cnt[..., None, None] * (ET[:, None] @ (q_th[:, None] * E)[None, :])
    )
    K = np.zeros((N, N, 6, 6))
    K[:, :, 0:3, 0:3] = dt * dt * T + cnt[..., None, None] * np.diag(q_w)
    diag_v = cnt[..., None] * q_v + (dt * dt) * Sp[..., None] * q_p  # (N, N, 3)
    K[:, :, 3, 3] = diag_v[..., 0]
    K[:, :, 4, 4] = diag_v[..., 1]
    K[:, :, 5, 5] = diag_v[..., 2]
    K_cols = np.ascontiguousarray(K.transpose(1, 0, 2, 3).reshape(N, 6 * N, 6))
    Iinv = np.swapaxes(RzT, 1, 2) @ Ib_inv @ RzT
    return Kernel(
        K_cols=K_cols,
        C=C,
        E=E,
        CT=np.ascontiguousarray(np.swapaxes(C, 1, 2)),
        ET=np.ascontiguousarray(np.swapaxes(E, 1, 2)),
        RzT=RzT,
        Iinv=Iinv,
    )


@dataclass(frozen=True, slots=True)
class StepTerms:
    """Per-step quantities of one problem (all world frame).

    ``Iinv`` (N, 3, 3) inverse world inertia, ``mass`` (N,), ``tau_ext`` (N, 3) and
    ``f_ext`` (N, 3) the known external torque about the lever origin and force (None when no
    object is held), ``Tw`` (N, 2, 3, 5) the torque of a unit foot-frame wrench,
    ``cos_foot``/``sin_foot`` (N, 2) of the foot yaws, ``Phi`` (N, 6, 10) the omega/pdot kicks
    of the 10 wrench components of step k (zero columns for swing feet), ``cols`` the stance
    variable indices into the 10N layout, in the QP's order: steps 1..N-1, then step 0.
    """

    Iinv: FloatArray
    mass: FloatArray
    tau_ext: FloatArray | None
    f_ext: FloatArray | None
    Tw: FloatArray
    cos_foot: FloatArray
    sin_foot: FloatArray
    Phi: FloatArray
    cols: npt.NDArray[np.intp]


def step_terms(inp: MpcInput, dt: float, Iinv_model2: FloatArray, Ib: FloatArray) -> StepTerms:
    """Per-step terms; ``Iinv_model2`` (N, 3, 3) is R_z I_body^-1 R_z^T at yaw_lin (cached)."""
    N = inp.horizon
    p_com = np.empty((N, 3))
    p_com[0] = inp.x0[srbd.POS]
    p_com[1:] = inp.x_ref[:-1, srbd.POS]
    mass = np.full(N, inp.mass)
    tau_ext: FloatArray | None = None
    f_ext: FloatArray | None = None
    m_o = np.broadcast_to(np.asarray(inp.object_mass, dtype=np.float64), (N,))
    held = inp.object_held & (m_o > 0.0)
    lever = p_com
    Iinv = Iinv_model2
    if held.any():
        assert inp.p_object is not None
        if inp.model == "combined":
            Rz = rot_z_stack(inp.yaw_lin)
            I_w = Rz @ Ib @ np.swapaxes(Rz, 1, 2)
            m_t = inp.mass + m_o
            p_h = (inp.mass * p_com + m_o[:, None] * inp.p_object) / m_t[:, None]
            d_c = p_com - p_h
            d_o = inp.p_object - p_h
            eye = np.eye(3)
            pm = inp.mass * (
                np.einsum("ki,ki->k", d_c, d_c)[:, None, None] * eye
                - d_c[:, :, None] * d_c[:, None, :]
            )
            pm += m_o[:, None, None] * (
                np.einsum("ki,ki->k", d_o, d_o)[:, None, None] * eye
                - d_o[:, :, None] * d_o[:, None, :]
            )
            I_w = np.where(held[:, None, None], I_w + pm, I_w)
            Iinv = np.asarray(np.linalg.inv(I_w), dtype=np.float64)
            mass = np.where(held, m_t, mass)
            lever = np.where(held[:, None], p_h, p_com)
        else:
            f_ext = np.zeros((N, 3))
            f_ext[held, 2] = -m_o[held] * srbd.GRAVITY
            tau_ext = np.cross(inp.p_object - p_com, f_ext)
    r = inp.p_feet - lever[:, None, :]  # (N, 2, 3)
    rx, ry, rz = r[..., 0], r[..., 1], r[..., 2]
    c, s = np.cos(inp.foot_yaw), np.sin(inp.foot_yaw)
    # Torque of a unit foot-frame wrench: columns r x e1', r x e2', r x e3 (the force part,
    # skew(r) R_f) and e2', e3 (the moments), with e1' = (c, s, 0), e2' = (-s, c, 0).
    Tw = np.zeros((N, 2, 3, 5))
    Tw[..., 0, 0] = -rz * s
    Tw[..., 1, 0] = rz * c
    Tw[..., 2, 0] = rx * s - ry * c
    Tw[..., 0, 1] = -rz * c
    Tw[..., 1, 1] = -rz * s
    Tw[..., 2, 1] = rx * c + ry * s
    Tw[..., 0, 2] = ry
    Tw[..., 1, 2] = -rx
    Tw[..., 0, 3] = -s
    Tw[..., 1, 3] = c
    Tw[..., 2, 4] = 1.0
    Phi4 = np.zeros((N, 6, 2, 5))
    Phi4[:, 0:3] = np.swapaxes((dt * Iinv)[:, None] @ Tw, 1, 2)
    kv = (dt / mass)[:, None]
    Phi4[:, 3, :, 0] = kv * c
    Phi4[:, 4, :, 0] = kv * s
    Phi4[:, 3, :, 1] = -kv * s
    Phi4[:, 4, :, 1] = kv * c
    Phi4[:, 5, :, 2] = kv
    Phi4 *= inp.contact[:, None, :, None]
    Phi = Phi4.reshape(N, 6, 10)
    cols = np.flatnonzero(np.repeat(inp.contact.reshape(-1), 5))
    # Step 0's variables last: only they depend on the measured state (through the lever
    # arms from x0's CoM), so the leading block of H repeats while the plan does.
    n0 = int(np.count_nonzero(cols < 10))
    cols = np.concatenate([cols[n0:], cols[:n0]])
    return StepTerms(
        Iinv=Iinv,
        mass=mass,
        tau_ext=tau_ext,
        f_ext=f_ext,
        Tw=Tw,
        cos_foot=c,
        sin_foot=s,
        Phi=Phi,
        cols=cols,
    )


def propagate(
    x0: FloatArray,
    RzT: FloatArray,
    Iinv: FloatArray,
    mass: FloatArray,
    tau: FloatArray | None,
    force: FloatArray | None,
    dt: float,
) -> FloatArray:
    """Exact ZOH rollout x_1..x_N (N, 15) of the SRBD under known per-step wrenches.

    x0 (15,), RzT (N, 3, 3) = R_z(yaw_lin_k)^T, Iinv (N, 3, 3) world inverse inertia (kg^-1
    m^-2), mass (N,) (kg), tau (N, 3) the torque about the CoM (N m) and force (N, 3) the
    contact plus external force (N), both world and constant over each step (None: zero).
    """
    N = RzT.shape[0]
    g0 = x0[srbd.GRAV]
    # a[:, 0:3] the omega kicks, a[:, 3:6] the velocity kicks of each step.
    a = np.empty((N, 6))
    if tau is None:
        a[:, 0:3] = 0.0
    else:
        a[:, 0:3] = dt * (Iinv @ tau[:, :, None])[:, :, 0]
    if force is None:
        a[:, 3:6] = dt * g0
    else:
        a[:, 3:6] = dt * (force / mass[:, None] + g0)
    WV = np.cumsum(a, axis=0)  # omega and velocity changes after each step
    w0v0 = x0[6:12]  # [omega; pdot], contiguous in the state
    mid = w0v0 + WV - 0.5 * a  # mean omega and velocity over each step
    rates = np.empty((N, 6))
    rates[:, 0:3] = (RzT @ mid[:, 0:3, None])[:, :, 0]
    rates[:, 3:6] = mid[:, 3:6]
    TP = dt * np.cumsum(rates, axis=0)  # Theta and position changes
    X = np.empty((N, srbd.NX))
    X[:, 0:6] = x0[0:6] + TP
    X[:, 6:12] = w0v0 + WV
    X[:, srbd.GRAV] = g0
    return X


def wrench_rows(s: MpcSettings) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Per stance foot: rows (m, 5) and bounds lo, hi with lo <= rows w <= hi."""
    mu = s.mu
    rows = [
        [1.0, 0.0, -mu, 0.0, 0.0],  # Fx' - mu Fz <= 0
        [1.0, 0.0, mu, 0.0, 0.0],  # Fx' + mu Fz >= 0
        [0.0, 1.0, -mu, 0.0, 0.0],
        [0.0, 1.0, mu, 0.0, 0.0],
        [0.0, 0.0, s.toe, 1.0, 0.0],  # My' + toe Fz >= 0
        [0.0, 0.0, -s.heel, 1.0, 0.0],  # My' - heel Fz <= 0
    ]
    inf = np.inf
    lo = [-inf, 0.0, -inf, 0.0, 0.0, -inf]
    hi = [0.0, inf, 0.0, inf, inf, 0.0]
    if s.mu_torsion is not None:
        rows += [[0.0, 0.0, -s.mu_torsion, 0.0, 1.0], [0.0, 0.0, s.mu_torsion, 0.0, 1.0]]
        lo += [-inf, 0.0]
        hi += [0.0, inf]
    return np.array(rows), np.array(lo), np.array(hi)
