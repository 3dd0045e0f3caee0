"""MuJoCo <-> pinocchio free-flyer conversions (pure numpy), checked against the libraries.

MuJoCo: qpos quaternion (w, x, y, z); qvel = [v_base_origin in WORLD axes, omega in BASE
axes, qdot]. pinocchio: q quaternion (x, y, z, w); v = [v_base_origin in BASE axes, omega in
BASE axes, qdot]. v_pin = T qvel with T = blkdiag(R^T, I3, I). The maps are exact up to
round-off, so the tolerances are 1e-12 (a few ulps of O(1) quantities).
"""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
from hypothesis import given, settings
from hypothesis import strategies as st

from locoplan.robot import conventions as cv

NQ, NV = 23, 22
finite = st.floats(-3.0, 3.0, allow_nan=False)


def _state(values: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """A MuJoCo state from 45 numbers (the quaternion normalised)."""
    qpos = np.array(values[:NQ])
    quat = qpos[3:7] + np.array([1.5, 0.0, 0.0, 0.0])  # keep it away from zero norm
    qpos[3:7] = quat / np.linalg.norm(quat)
    return qpos, np.array(values[NQ : NQ + NV])


@settings(max_examples=50, deadline=None)
@given(st.lists(finite, min_size=NQ + NV, max_size=NQ + NV))
def test_round_trips(values: list[float]) -> None:
    qpos, qvel = _state(values)
    q = cv.mj_to_pin_q(qpos)
    assert np.allclose(cv.pin_to_mj_q(q), qpos, atol=1e-12, rtol=0)
    v = cv.mj_to_pin_v(qpos, qvel)
    assert np.allclose(cv.pin_to_mj_v(q, v), qvel, atol=1e-12, rtol=0)
    T = cv.velocity_transform(cv.mj_base_rotation(qpos), NV)
    assert np.allclose(T @ qvel, v, atol=1e-12, rtol=0)
    assert np.allclose(T.T @ T, np.eye(NV), atol=1e-12, rtol=0)
    tau = np.arange(NV, dtype=float)
    assert np.allclose(cv.mj_to_pin_force(qpos, cv.pin_to_mj_force(q, tau)), tau, atol=1e-12)
    # Power is the same in both bases.
    assert abs(cv.pin_to_mj_force(q, tau) @ qvel - tau @ v) < 1e-10
    a = np.linspace(-1.0, 1.0, NV)
    assert np.allclose(cv.mj_to_pin_a(qpos, qvel, cv.pin_to_mj_a(q, v, a)), a, atol=1e-12)


def test_rotation_matches_libraries() -> None:
    rng = np.random.default_rng(3)
    for _ in range(20):
        quat = rng.normal(size=4)
        quat /= np.linalg.norm(quat)
        R_mj = np.zeros(9)
        mujoco.mju_quat2Mat(R_mj, quat)
        assert np.allclose(cv.quat_wxyz_to_rotation(quat), R_mj.reshape(3, 3), atol=1e-12)
        q = cv.mj_to_pin_q(np.concatenate([[0.1, 0.2, 0.3], quat, np.zeros(16)]))
        R_pin = pin.Quaternion(q[3:7]).matrix()  # pinocchio's (x, y, z, w) order
        assert np.allclose(cv.pin_base_rotation(q), R_pin, atol=1e-12)


def test_mj_to_pin_q_normalises_quaternion() -> None:
    qpos = np.zeros(NQ)
    qpos[3:7] = [2.0, 0.0, 0.0, 0.0]
    q = cv.mj_to_pin_q(qpos)
    assert np.array_equal(q[3:7], [0.0, 0.0, 0.0, 1.0])


def test_acceleration_drift_is_derivative_of_T() -> None:
    """a_pin = T a_mj + c: c is d/dt(T) qvel, checked by finite differences of T(q(t)) qvel.

    Along a motion with constant MuJoCo qvel the base rotates at omega (base axes); central
    differences with h = 1e-6 are accurate to ~1e-10 here.
    """
    rng = np.random.default_rng(5)
    qpos, qvel = _state(list(rng.uniform(-1, 1, NQ + NV)))
    h = 1e-6
    model = pin.Model()
    model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    q = cv.mj_to_pin_q(qpos)[:7]
    v_pin = cv.mj_to_pin_v(qpos, qvel)[:6]
    vs = []
    for t in (-h, h):
        qt = pin.integrate(model, q, t * v_pin)
        vs.append(cv.velocity_transform(cv.pin_base_rotation(qt), 6) @ qvel[:6])
    fd = (vs[1] - vs[0]) / (2 * h)
    assert np.allclose(cv.basis_change_drift(v_pin), fd, atol=1e-8)


def _reference_rotation(quat_wxyz: np.ndarray) -> np.ndarray:
    """The numpy expression the fast path must reproduce bit for bit."""
    w, x, y, z = np.asarray(quat_wxyz, dtype=np.float64) / np.linalg.norm(quat_wxyz)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def test_state_conversion_is_bit_for_bit_the_reference() -> None:
    """`mj_to_pin_state` (the closed loop's per-tick call) gives exactly the numbers of the
    separate conversions and of the plain numpy formulas (no tolerance: the controller must
    see the same state whichever path computed it), also for unnormalised quaternions."""
    rng = np.random.default_rng(11)
    for k in range(2000):
        qpos = rng.normal(size=NQ) * rng.uniform(0.1, 3.0)
        qvel = rng.normal(size=NV) * 3.0
        if k % 2:
            qpos[3:7] /= np.linalg.norm(qpos[3:7])
        q, v = cv.mj_to_pin_state(qpos, qvel)
        assert np.array_equal(q, cv.mj_to_pin_q(qpos))
        assert np.array_equal(v, cv.mj_to_pin_v(qpos, qvel))
        R = _reference_rotation(qpos[3:7])
        assert np.array_equal(cv.quat_wxyz_to_rotation(qpos[3:7]), R)
        assert np.array_equal(v[0:3], R.T @ qvel[0:3])
        quat = qpos[3:7] / np.linalg.norm(qpos[3:7])
        assert np.array_equal(q[3:7], quat[[1, 2, 3, 0]])
        assert np.array_equal(cv.pin_base_rotation(q), _reference_rotation(quat))
