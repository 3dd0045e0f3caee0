"""Tests of locoplan.control.srbd: the linearised SRBD, its exact discretisation, Model 1."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from locoplan.control import srbd

MASS = 17.0
INERTIA = np.diag([0.17, 0.15, 0.06])
P_FEET = np.array([[0.02, 0.1, 0.0], [-0.03, -0.1, 0.0]])


def _model(
    contact: tuple[bool, bool] = (True, True),
    held: bool = True,
    model: str = "external-force",
    yaw: float = 0.7,
) -> srbd.ContinuousModel:
    return srbd.continuous_model(
        yaw=yaw,
        p_com_world=np.array([0.01, 0.0, 0.55]),
        p_feet_world=P_FEET,
        foot_yaw=np.array([0.6, 0.8]),
        contact=np.array(contact),
        mass=MASS,
        inertia_body=INERTIA,
        object_held=held,
        object_mass=4.0,
        p_object_world=np.array([0.3, 0.05, 0.6]),
        model=model,
    )


def _state(rng: np.random.Generator) -> np.ndarray:
    x = np.zeros(15)
    x[:12] = 0.1 * rng.normal(size=12)
    x[srbd.POS] += [0.0, 0.0, 0.55]
    x[srbd.GRAV] = srbd.gravity_state()
    return x


@pytest.mark.parametrize("model", ["external-force", "combined"])
@pytest.mark.parametrize("contact", [(True, True), (True, False), (False, False)])
def test_polynomial_zoh_equals_matrix_exponential(model: str, contact: tuple[bool, bool]) -> None:
    cm = _model(contact, model=model)
    exact = srbd.discretize(cm, 0.03)
    ref = srbd.discretize_expm(cm, 0.03)
    # expm's Pade approximation is accurate to ~1e-15 relative; entries are O(1) to O(10).
    for a, b in ((exact.A, ref.A), (exact.B, ref.B), (exact.d, ref.d)):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)


def test_structure_is_nilpotent() -> None:
    cm = _model()
    A2 = cm.A @ cm.A
    assert np.all(A2 @ cm.A == 0.0)
    assert np.all(A2 @ cm.B == 0.0) and np.all(A2 @ cm.d == 0.0)
    bad = srbd.ContinuousModel(A=np.eye(15), B=cm.B, d=cm.d)
    with pytest.raises(ValueError):
        srbd.discretize(bad, 0.03)


@pytest.mark.parametrize("contact", [(True, True), (False, True)])
def test_discretisation_matches_rk4_rollout(contact: tuple[bool, bool]) -> None:
    # The continuous solution under a constant input is a quadratic polynomial in t (A^3 = 0),
    # which RK4 integrates exactly, so 100 RK4 substeps agree with the ZOH model to rounding:
    # 1e-10 on states of size <= 10 leaves a wide margin over the ~1e-14 seen.
    rng = np.random.default_rng(0)
    cm = _model(contact)
    dm = srbd.discretize(cm, 0.03)
    for _ in range(5):
        x0 = _state(rng)
        u = srbd.input_vector(rng.normal(scale=50.0, size=(2, 3)), rng.normal(size=(2, 2)))
        x_rk4 = srbd.rk4_rollout(cm, x0, u, 0.03, substeps=100)
        np.testing.assert_allclose(dm.A @ x0 + dm.B @ u + dm.d, x_rk4, rtol=0, atol=1e-10)


def test_rollout_over_several_steps_matches_rk4() -> None:
    rng = np.random.default_rng(1)
    models_c = [_model(c, yaw=0.1 * k) for k, c in enumerate([(True, True), (True, False)] * 3)]
    x0 = _state(rng)
    u = rng.normal(scale=40.0, size=(6, 10))
    X = srbd.rollout([srbd.discretize(cm, 0.03) for cm in models_c], x0, u)
    x = x0
    for k, cm in enumerate(models_c):
        x = srbd.rk4_rollout(cm, x, u[k], 0.03, substeps=50)
        np.testing.assert_allclose(X[k], x, rtol=0, atol=1e-10)  # as above, rounding only


def test_euler_rate_convention_matches_rotation_kinematics() -> None:
    # Theta_dot = R_z(psi)^T omega at zero roll/pitch: compare with the ZYX Euler angles of
    # R(t) = exp(skew(omega) t) R_z(psi) by a central difference (error O(h^2) ~ 1e-9).
    psi = 0.9
    omega = np.array([0.3, -0.2, 0.5])
    R0 = Rotation.from_euler("ZYX", [psi, 0.0, 0.0])
    h = 1e-5

    def rpy(t: float) -> np.ndarray:
        R = Rotation.from_rotvec(omega * t) * R0
        yaw, pitch, roll = R.as_euler("ZYX")
        return np.array([roll, pitch, yaw])

    rate = (rpy(h) - rpy(-h)) / (2 * h)
    cm = _model(yaw=psi)
    np.testing.assert_allclose(cm.A[srbd.THETA, srbd.OMEGA] @ omega, rate, atol=1e-8)


def test_model2_external_force_is_affine_and_pitches_forward() -> None:
    cm = _model(held=True)
    m_o = 4.0
    F_ext = np.array([0.0, 0.0, -m_o * srbd.GRAVITY])
    r_e = np.array([0.3, 0.05, 0.6]) - np.array([0.01, 0.0, 0.55])
    I_w = srbd.inertia_world(INERTIA, 0.7)
    np.testing.assert_allclose(cm.d[srbd.VEL], F_ext / MASS, atol=1e-12)
    np.testing.assert_allclose(
        cm.d[srbd.OMEGA], np.linalg.solve(I_w, np.cross(r_e, F_ext)), atol=1e-12
    )
    # A load in front (+x) gives a positive torque about y: nose down.
    assert np.cross(r_e, F_ext)[1] > 0.0
    assert np.all(_model(held=False).d == 0.0)


def test_contact_columns_and_line_foot_moment() -> None:
    cm = _model((True, False), held=False)
    assert np.all(cm.B[:, 3:6] == 0.0) and np.all(cm.B[:, 8:10] == 0.0)
    np.testing.assert_allclose(cm.B[srbd.VEL, 0:3], np.eye(3) / MASS)
    # M_1 = [My, Mz] in the foot's yaw frame maps to R_z(psi_foot) [0, My, Mz] in the world.
    I_w = srbd.inertia_world(INERTIA, 0.7)
    M_world = srbd.rot_z(0.6) @ np.array([0.0, 2.0, -1.0])
    np.testing.assert_allclose(
        cm.B[srbd.OMEGA, 6:8] @ np.array([2.0, -1.0]), np.linalg.solve(I_w, M_world), atol=1e-12
    )


def test_combined_body_parallel_axis() -> None:
    # Two point masses on the x axis: I_yy = I_zz = sum m d^2 about the combined CoM.
    body = srbd.combined_body(
        2.0, np.zeros((3, 3)), np.array([0.0, 0.0, 0.0]), 1.0, np.array([0.3, 0.0, 0.0])
    )
    assert body.mass == 3.0
    np.testing.assert_allclose(body.p_com_world, [0.1, 0.0, 0.0])
    expected = 2.0 * 0.1**2 + 1.0 * 0.2**2
    np.testing.assert_allclose(body.inertia_world, np.diag([0.0, expected, expected]), atol=1e-15)


def test_model1_uses_combined_mass_and_no_external_force() -> None:
    cm = _model(held=True, model="combined")
    assert np.all(cm.d == 0.0)
    np.testing.assert_allclose(cm.B[srbd.VEL, 0:3], np.eye(3) / (MASS + 4.0))
    with pytest.raises(ValueError):
        _model(model="bogus")
