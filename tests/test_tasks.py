"""Task stacking for the WBC (locoplan.control.tasks) on recorded walking ticks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from wbc_fixtures import n_ticks, recording, task_args

from locoplan.control.tasks import build_tasks, rot_z, rotation_error


def _reference_tasks(args: tuple) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The task stack written out plainly (vstack / concatenate, R' J), as (J, jdot_v, xdd)."""
    (g, q, v, R, omega, p_des, v_des, yaw_des, yaw_rate, J_base, dJv_base, stance) = args[:12]
    (J_feet, dJv_feet, v_feet, p_feet, R_feet, swing, J_hands, dJv_hands, hand_acc) = args[12:]

    def foot_rows(k: int) -> tuple[np.ndarray, np.ndarray]:
        Rf = R_feet[k]
        return (
            np.vstack([J_feet[k][:3], (Rf.T @ J_feet[k][3:])[1:]]),
            np.concatenate([dJv_feet[k][:3], (Rf.T @ dJv_feet[k][3:])[1:]]),
        )

    out = []
    rows = [foot_rows(k) for k in range(2) if stance[k]]
    if rows:
        Jc = np.vstack([r[0] for r in rows])
        out.append((Jc, np.concatenate([r[1] for r in rows]), np.zeros(Jc.shape[0])))
    e = rotation_error(rot_z(yaw_des), R)
    acc_rot = np.array(g.trunk_kp_rot) * e + np.array(g.trunk_kd_rot) * (
        np.array([0.0, 0.0, yaw_rate]) - omega
    )
    acc_pos = np.array(g.trunk_kp_pos) * (p_des - q[:3]) + np.array(g.trunk_kd_pos) * (
        v_des - R @ v[:3]
    )
    out.append((J_base, dJv_base, np.concatenate([acc_pos, acc_rot])))
    Js, bs, accs = [], [], []
    swing_feet = [k for k in range(2) if not stance[k]]
    for (p_d, v_d, a_d, yaw_d), k in zip(swing, swing_feet, strict=False):
        Rf = R_feet[k]
        a_lin = a_d + g.swing_kp * (p_d - p_feet[k]) + g.swing_kd * (v_d - v_feet[k][:3])
        a_ang = g.swing_kp_rot * (Rf.T @ rotation_error(rot_z(yaw_d), Rf)) - g.swing_kd_rot * (
            Rf.T @ v_feet[k][3:]
        )
        J5, b5 = foot_rows(k)
        Js.append(J5)
        bs.append(b5)
        accs.append(np.concatenate([a_lin, a_ang[1:]]))
    for k in range(2):
        Js.append(J_hands[k])
        bs.append(dJv_hands[k])
        accs.append(hand_acc[k])
    out.append((np.vstack(Js), np.concatenate(bs), np.concatenate(accs)))
    return out


def test_build_tasks_matches_plain_stacking_on_recorded_ticks() -> None:
    assert n_ticks() > 100
    for i in range(n_ticks()):
        args = task_args(i)
        got = build_tasks(*args)
        want = _reference_tasks(args)
        assert len(got) == len(want)
        for task, (J, b, a) in zip(got, want, strict=True):
            # Same arithmetic up to operation order: rounding only (values up to ~1e3).
            np.testing.assert_allclose(task.J, J, rtol=0, atol=1e-12)
            np.testing.assert_allclose(task.jdot_v, b, rtol=0, atol=1e-10)
            np.testing.assert_allclose(task.xdd_des, a, rtol=0, atol=1e-9)


def test_task_shapes_follow_the_stance() -> None:
    rec = recording()
    for i in range(n_ticks()):
        tasks = build_tasks(*task_args(i))
        n_st = int(rec["stance"][i].sum())
        n_sw = int(rec["n_swing"][i])
        assert [t.J.shape[0] for t in tasks] == [5 * n_st, 6, 5 * n_sw + 6]
        assert not np.any(tasks[0].xdd_des)


@pytest.mark.parametrize("seed", range(5))
def test_rotation_error_is_the_log_map(seed: int) -> None:
    rng = np.random.default_rng(seed)
    R = Rotation.random(random_state=rng).as_matrix()
    e_true = rng.normal(size=3)
    e_true *= rng.uniform(0.0, 3.0) / np.linalg.norm(e_true)
    R_des = Rotation.from_rotvec(e_true).as_matrix() @ R
    e = rotation_error(R_des, R)
    # acos near a well-conditioned angle (< 3 rad): 1e-9 is far above rounding.
    np.testing.assert_allclose(e, e_true, atol=1e-9)
    np.testing.assert_allclose(Rotation.from_rotvec(e).as_matrix() @ R, R_des, atol=1e-9)


def test_rotation_error_small_angle_branch() -> None:
    R = rot_z(0.4)
    e_true = np.array([3e-7, -2e-7, 1e-7])
    R_des = Rotation.from_rotvec(e_true).as_matrix() @ R
    # Below 1e-6 rad the sin(theta)/theta factor is taken as 1: error O(theta^3) plus rounding.
    np.testing.assert_allclose(rotation_error(R_des, R), e_true, atol=1e-12)
    assert not np.any(rotation_error(R, R))


def test_rot_z() -> None:
    np.testing.assert_allclose(rot_z(0.7), Rotation.from_euler("z", 0.7).as_matrix(), atol=1e-15)
    assert math.isclose(float(np.linalg.det(rot_z(-2.0))), 1.0)
