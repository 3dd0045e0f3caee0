"""The controller's joint posture task: which joints it holds, and that it acts only in the
exact null space of the task stack (no simulation)."""

from __future__ import annotations

import numpy as np
import pytest

from locoplan.control.controller import (
    posture_acceleration,
    posture_in_null_space,
    posture_joint_indices,
)
from locoplan.robot.description import load_robot_description


def test_hector_has_no_posture_joint_h1_has_torso_and_arms() -> None:
    assert len(posture_joint_indices(load_robot_description("hector"))) == 0
    h1 = load_robot_description("h1")
    held = [h1.joint_names[j] for j in posture_joint_indices(h1)]
    assert held == [
        "torso_yaw",
        *(
            f"{s}_{n}"
            for s in "LR"
            for n in ("shoulder_pitch", "shoulder_roll", "shoulder_yaw", "elbow")
        ),
    ]


def test_posture_acceleration_is_a_joint_pd() -> None:
    # nv = 6 + 3 joints; q has the quaternion's extra entry, so joint j sits at q[7 + j].
    q = np.zeros(10)
    q[7:] = (0.1, -0.2, 0.3)
    v = np.zeros(9)
    v[6:] = (1.0, 2.0, 3.0)
    cols = np.array([6, 8])
    a = posture_acceleration(cols, np.array([0.0, 0.5]), q, v, 100.0, 20.0)
    assert np.allclose(a, [100.0 * -0.1 - 20.0 * 1.0, 100.0 * 0.2 - 20.0 * 3.0], atol=1e-12)


def test_posture_moves_no_task_above_and_is_the_least_squares_in_the_null_space() -> None:
    rng = np.random.default_rng(14)
    nv = 25
    J = rng.normal(size=(22, nv))  # H1 in double support: 22 rows, a 3-D null space
    qdd = rng.normal(size=nv)
    cols = np.arange(16, 25)
    a = rng.normal(size=9) * 50.0
    d = posture_in_null_space(J, cols, a, qdd)
    # Round-off of an SVD of O(1) entries: 1e-10 is far below any task acceleration.
    assert np.max(np.abs(J @ d)) < 1e-10
    # Any other null-space correction leaves the posture residual no smaller.
    Z = np.linalg.svd(J)[2][22:].T
    best = np.linalg.norm(a - (qdd + d)[cols])
    for _ in range(50):
        other = Z @ rng.normal(size=3)
        assert np.linalg.norm(a - (qdd + other)[cols]) >= best - 1e-9


@pytest.mark.parametrize("rows", [25, 30])
def test_no_null_space_no_posture(rows: int) -> None:
    rng = np.random.default_rng(rows)
    J = rng.normal(size=(rows, 25))
    d = posture_in_null_space(J, np.arange(3), np.ones(3), np.zeros(25))
    assert np.array_equal(d, np.zeros(25))
