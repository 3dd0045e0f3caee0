"""Trunk reference (locoplan.plan.trunk): exact end poses, rest at the ends, derivatives."""

from __future__ import annotations

import math

import numpy as np
import pytest
from plan_fixtures import repo_scenario, scenario_from_text

from locoplan.plan import compile_plan
from locoplan.plan.profiles import cruise_array
from locoplan.plan.trunk import TrunkPath

TURN_WALK = """
version: 1
name: turn-walk
robot_start: {position: [0.3, -0.2], yaw: 30}
tasks:
  - {action: turn, angle: 90, start: 0.5, duration: 1.6}
  - {action: walk, distance: [0.4, 0.1], start: 2.3, duration: 2.0}
  - {action: turn, angle: -45, start: 4.3, duration: 1.2}
"""


def test_turn_reaches_commanded_yaw_exactly_at_rest() -> None:
    plan = compile_plan(scenario_from_text(TURN_WALK))
    turn = plan.tasks[0]
    yaw0 = math.radians(30.0)
    ref = plan.trunk_reference(np.array([turn.start, turn.end, turn.end + 0.1]))
    # 1e-12 rad: the min-jerk blend is exactly 1.0 at tau = 1, so only the sum rounds.
    assert ref.yaw[0] == pytest.approx(yaw0, abs=1e-12)
    assert ref.yaw[1] == pytest.approx(yaw0 + math.radians(90.0), abs=1e-12)
    assert ref.yaw[2] == ref.yaw[1]
    assert ref.yaw_rate[0] == 0.0 and ref.yaw_rate[1] == 0.0
    assert np.all(ref.position[:, :2] == ref.position[0, :2])  # turning in place
    scalar = plan.trunk_reference_at(turn.end)
    assert scalar.yaw == pytest.approx(yaw0 + math.pi / 2, abs=1e-12)
    assert scalar.yaw_rate == 0.0


def test_walk_reaches_body_frame_displacement_exactly() -> None:
    plan = compile_plan(scenario_from_text(TURN_WALK))
    walk = plan.tasks[1]
    heading = math.radians(30.0 + 90.0)  # "forward" is the heading after the first turn
    c, s = math.cos(heading), math.sin(heading)
    expected = np.array([0.3 + c * 0.4 - s * 0.1, -0.2 + s * 0.4 + c * 0.1, 0.6])
    ref = plan.trunk_reference(np.array([walk.start, walk.end]))
    assert ref.position[0] == pytest.approx([0.3, -0.2, 0.6], abs=1e-12)
    # 1e-12 m: exact blend end, rounding of one rotation and one sum only.
    assert ref.position[1] == pytest.approx(expected, abs=1e-12)
    assert np.all(ref.velocity[1] == 0.0) and np.all(ref.acceleration[1] == 0.0)
    assert ref.yaw[0] == ref.yaw[1] == pytest.approx(heading, abs=1e-12)
    x, y, yaw = plan.final_pose
    assert (x, y) == pytest.approx(tuple(expected[:2]), abs=1e-12)
    assert yaw == pytest.approx(heading - math.pi / 4, abs=1e-12)


def test_walk_square_closes() -> None:
    plan = compile_plan(repo_scenario("walk-square"))
    x, y, yaw = plan.final_pose
    assert (x, y) == pytest.approx((0.0, 0.0), abs=1e-12)  # four 0.5 m sides, float rounding
    assert yaw == pytest.approx(2.0 * math.pi, abs=1e-12)


def test_vectorised_equals_scalar_and_velocity_matches_finite_differences() -> None:
    plan = compile_plan(scenario_from_text(TURN_WALK))
    times = np.linspace(-0.2, plan.t_end + 0.2, 1501)
    ref = plan.trunk_reference(times)
    for i in range(0, times.size, 7):
        st = plan.trunk_reference_at(float(times[i]))
        assert st.position == pytest.approx(ref.position[i], abs=1e-14)
        assert st.velocity == pytest.approx(ref.velocity[i], abs=1e-14)
        assert st.yaw == pytest.approx(ref.yaw[i], abs=1e-14)
        assert st.yaw_rate == pytest.approx(ref.yaw_rate[i], abs=1e-14)
    h = 1e-6
    plus, minus = plan.trunk_reference(times + h), plan.trunk_reference(times - h)
    # central differences of a quintic: error ~ h^2 * third derivative (< 100 /s^3) ~ 1e-10,
    # plus rounding ~ 1e-16 / 1e-6; 1e-7 leaves margin.
    assert (plus.position - minus.position) / (2 * h) == pytest.approx(ref.velocity, abs=1e-7)
    assert (plus.yaw - minus.yaw) / (2 * h) == pytest.approx(ref.yaw_rate, abs=1e-7)
    assert (plus.velocity - minus.velocity) / (2 * h) == pytest.approx(ref.acceleration, abs=1e-6)
    assert np.all(ref.position[:, 2] == 0.6)


def test_base_height_and_bad_arguments() -> None:
    scenario = scenario_from_text(TURN_WALK)
    plan = compile_plan(scenario, base_height=0.58)
    assert plan.trunk_reference_at(1.0).position[2] == 0.58
    with pytest.raises(ValueError, match="base_height"):
        compile_plan(scenario, base_height=0.0)
    with pytest.raises(ValueError, match="foot_width"):
        compile_plan(scenario, foot_width=-0.1)


def test_walks_and_turns_peak_at_one_and_a_half_times_their_average() -> None:
    """The cruise profile: the speed ramps over the first and last thirds, so the peak is
    1.5 x distance / duration, and the peak acceleration 1.5 x peak / (duration / 3) =
    6.75 x distance / duration^2 (min-jerk: 1.875 and 5.77). Sampled every 0.1 ms: the
    plateau is sampled exactly, the acceleration peak (mid-ramp) to 1e-6 relative."""
    plan = compile_plan(scenario_from_text(TURN_WALK))
    walk, turn = plan.tasks[1], plan.tasks[0]
    for task, amount, pick in (
        (
            walk,
            math.hypot(0.4, 0.1),
            lambda r: (
                np.linalg.norm(r.velocity[:, :2], axis=1),
                np.linalg.norm(r.acceleration[:, :2], axis=1),
            ),
        ),
        (turn, math.radians(90.0), lambda r: (np.abs(r.yaw_rate), np.abs(r.yaw_acceleration))),
    ):
        duration = task.end - task.start
        ref = plan.trunk_reference(np.linspace(task.start, task.end, int(duration * 1e4) + 1))
        speed, accel = pick(ref)
        assert speed.max() == pytest.approx(1.5 * amount / duration, rel=1e-12)
        assert accel.max() == pytest.approx(6.75 * amount / duration**2, rel=1e-6)
        # The plateau: the middle third moves at the peak speed.
        mid = (ref.yaw_rate if task is turn else speed)[speed.size // 3 + 1 : 2 * speed.size // 3]
        assert np.allclose(np.abs(mid), 1.5 * amount / duration, rtol=1e-12)


def _numpy_evaluate(path: TrunkPath, t: np.ndarray) -> tuple[np.ndarray, ...]:
    """The trunk reference as numpy computed it before it was compiled (the reference the
    kernel must match bit for bit: `trunk_kernels`)."""
    i = np.searchsorted(path._t0, t, side="right") - 1
    dur = path._dur[i]
    s, ds, dds = cruise_array((t - path._t0[i]) / dur)
    dp = path._dp[i]
    pos = np.empty((t.shape[0], 3))
    pos[:, :2] = path._p0[i] + s[:, None] * dp
    pos[:, 2] = path.height
    vel = np.zeros((t.shape[0], 3))
    vel[:, :2] = (ds / dur)[:, None] * dp
    acc = np.zeros((t.shape[0], 3))
    acc[:, :2] = (dds / (dur * dur))[:, None] * dp
    dyaw = path._dyaw[i]
    return (
        pos,
        vel,
        acc,
        path._yaw0[i] + s * dyaw,
        ds / dur * dyaw,
        dds / (dur * dur) * dyaw,
    )


def test_compiled_reference_is_the_numpy_one_bit_for_bit() -> None:
    plan = compile_plan(scenario_from_text(TURN_WALK))
    rng = np.random.default_rng(7)
    # Before the first task, inside every ramp and cruise, on the segments' ends, after all.
    ends = [x for task in plan.tasks for x in (task.start, task.end)]
    t = np.concatenate([rng.uniform(-0.5, 6.5, 400), ends, [0.0, -1.0, 100.0]])
    ref = plan.trunk_reference(t)
    got = (
        ref.position,
        ref.velocity,
        ref.acceleration,
        ref.yaw,
        ref.yaw_rate,
        ref.yaw_acceleration,
    )
    for a, b in zip(got, _numpy_evaluate(plan.trunk, t), strict=True):
        np.testing.assert_array_equal(a, b)
    # The scalar path agrees to rounding (it is `profiles.cruise`, written apart).
    for k in range(0, t.shape[0], 37):
        x, y, yaw, vx, vy, wz = plan.trunk.pose_at(float(t[k]))
        assert (x, y, yaw, vx, vy, wz) == pytest.approx(
            (*ref.position[k, :2], ref.yaw[k], *ref.velocity[k, :2], ref.yaw_rate[k]), abs=1e-12
        )
