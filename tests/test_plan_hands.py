"""Hand target tracks (locoplan.plan.hands): continuity, rest at segment ends, velocities."""

from __future__ import annotations

import math

import numpy as np
import pytest
from plan_fixtures import repo_scenario, scenario_files

from locoplan.plan import Plan, compile_plan
from locoplan.plan.constants import (
    CARRY_HEIGHT,
    CARRY_IN_GAP,
    GRASP_ABOVE_CENTRE,
    GRASP_SQUEEZE,
    HAND_DEFAULT_IN_TRUNK,
    HAND_RADIUS,
    HAND_TUCK_IN_TRUNK,
    TRUNK_FRONT,
)
from locoplan.plan.hand_paths import pull_accel
from locoplan.scenario import load_scenario
from locoplan.sim.robot_plan import compile_robot_plan


def rest_to_rest(distance: float, mass: float) -> float:
    """Duration (s) of the quintic rest-to-rest move over `distance` (m) peaking at
    `pull_accel(mass)`: its peak acceleration is 10 / sqrt(3) d / T^2."""
    return math.sqrt(10.0 / math.sqrt(3.0) * distance / pull_accel(mass))


def _targets_along_plan(plan: Plan, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hand positions and velocities (n, 2, 3) with the trunk on its planned reference."""
    p = np.empty((times.size, 2, 3))
    v = np.empty((times.size, 2, 3))
    for i, t in enumerate(times):
        st = plan.trunk_reference_at(float(t))
        ht = plan.hand_targets_at(float(t), st.position, st.yaw)
        p[i] = ht.positions
        v[i] = ht.velocities
    return p, v


@pytest.mark.parametrize("path", scenario_files(), ids=lambda p: p.stem)
def test_hand_targets_continuous_and_velocity_consistent(path) -> None:
    plan = compile_robot_plan(load_scenario(path))
    boundaries = np.array(
        sorted({t for tr in plan.manipulation.tracks for g in tr.segments for t in (g.t0, g.t1)})
        or [0.5 * plan.t_end]
    )
    # Continuity across every segment boundary: hand speeds stay below 2 m/s, so 2e-7 s
    # apart the targets differ by < 4e-7 m; a mismatch between segments would be millimetres.
    eps = 1e-7
    p_before, _ = _targets_along_plan(plan, boundaries - eps)
    p_after, _ = _targets_along_plan(plan, boundaries + eps)
    assert np.abs(p_after - p_before).max() < 1e-6
    # The velocity output is the time derivative of the position output (the trunk moving
    # along its plan), at random times and next to every boundary. Central differences with
    # h = 1e-6 s: truncation h^2 jerk / 6 < 1e-9 m/s (jerk < 1e3 m/s^3), rounding ~1e-10 m/s;
    # acceleration is continuous at the boundaries, so 1e-6 m/s has ample margin.
    rng = np.random.default_rng(1)
    times = np.concatenate(
        [rng.uniform(0.0, plan.t_end, 1500), boundaries - 1e-4, boundaries + 1e-4]
    )
    h = 1e-6
    p_plus, _ = _targets_along_plan(plan, times + h)
    p_minus, _ = _targets_along_plan(plan, times - h)
    _, v = _targets_along_plan(plan, times)
    assert np.abs((p_plus - p_minus) / (2 * h) - v).max() < 1e-6


@pytest.mark.parametrize("name", ["package-transfer", "pick-walk-drop", "throw", "standing-load"])
def test_hands_at_rest_at_segment_ends_relative_to_their_frame(name) -> None:
    plan = compile_plan(repo_scenario(name))
    for track in plan.manipulation.tracks:
        for g in track.segments:
            for t, w in ((g.t0, g.start), (g.t1, g.end)):
                if any(w.velocity):
                    continue  # the throw's release point moves on purpose
                # World waypoints: a still trunk and a moving one give zero target velocity;
                # trunk waypoints: the target moves exactly with the trunk.
                base = np.array([0.1, -0.2, 0.6])
                ht = plan.hand_targets_at(t, base, 0.3, np.zeros(3), 0.0)
                vel = ht.v_L_world if track.hand == "L" else ht.v_R_world
                assert np.linalg.norm(vel) < 1e-12


def test_hands_start_tucked_when_the_default_pose_would_sweep_into_the_scene() -> None:
    # package-transfer turns 90 deg left towards a table whose near edge is 0.25 m away: the
    # left hand held 0.28 m ahead would sweep into it, so it starts (and rests) tucked; the
    # right hand, on the far side, keeps the default pose.
    plan = compile_plan(repo_scenario("package-transfer"))
    assert plan.manipulation.tracks[0].initial.point == pytest.approx(HAND_TUCK_IN_TRUNK)
    x, y, z = HAND_DEFAULT_IN_TRUNK
    assert plan.manipulation.tracks[1].initial.point == pytest.approx((x, -y, z))
    # with nothing near the robot they start in the default pose
    stand = compile_plan(repo_scenario("stand"))
    assert stand.manipulation.tracks[0].initial.point == pytest.approx(HAND_DEFAULT_IN_TRUNK)


def test_default_pose_before_any_task_follows_trunk() -> None:
    plan = compile_plan(repo_scenario("walk-square"))
    base = np.array([1.0, 2.0, 0.6])
    yaw = math.radians(40.0)
    ht = plan.hand_targets_at(0.0, base, yaw, np.array([0.2, 0.0, 0.0]), 0.5)
    x, y, z = HAND_DEFAULT_IN_TRUNK
    c, s = math.cos(yaw), math.sin(yaw)
    assert ht.p_L_world == pytest.approx(
        base + np.array([c * x - s * y, s * x + c * y, z]), abs=1e-15
    )
    assert ht.p_R_world == pytest.approx(
        base + np.array([c * x + s * y, s * x - c * y, z]), abs=1e-15
    )
    # rigid motion with the trunk: v = v_base + w x r
    r = np.array([c * x - s * y, s * x + c * y, z])
    assert ht.v_L_world == pytest.approx([0.2 - 0.5 * r[1], 0.5 * r[0], 0.0], abs=1e-15)
    assert not plan.hand_active("L", 0.0)


def test_pick_targets_and_carry_pose() -> None:
    plan = compile_plan(repo_scenario("package-transfer"))
    pick = next(t for t in plan.tasks if t.action == "pick")
    hold = plan.holds[0]
    # the box (0.15 m tall) is gripped GRASP_ABOVE_CENTRE above its centre, so that it hangs
    # level from the two point contacts
    assert hold.grip_height == GRASP_ABOVE_CENTRE
    z_grip = 0.545 + GRASP_ABOVE_CENTRE
    # the robot turns in place at the origin, the package is at +y: approach along +y, the
    # grasp axis along x with the left hand on the robot's left after the turn (-x side);
    # the hands close in until their spheres touch the sides, then press GRASP_SQUEEZE in
    grip = next(g for g in plan.manipulation.tracks[0].segments if g.label == "grip")
    assert grip.start.frame == "world" and grip.end.frame == "world"
    assert grip.start.point == pytest.approx((-(0.10 + HAND_RADIUS), 0.35, z_grip), abs=1e-12)
    assert grip.end.point == pytest.approx((-(0.10 - GRASP_SQUEEZE), 0.35, z_grip), abs=1e-12)
    # the package is carried through the turn that follows: the raise pulls it in (world
    # frame, along the approach +y) no faster than `pull_accel` for its 3 kg (a 0.3 s
    # rest-to-rest move: some 2 cm); then the "carry" move goes up to the carry height and
    # in at once until the box's near face is CARRY_IN_GAP from the trunk's front (its half
    # depth 0.10 m), CARRY_HEIGHT above the trunk origin, taking as long as `pull_accel` asks
    # for the whole (3D) move: past the pick's end, well before the drop; no "pull" is left
    segments = plan.manipulation.tracks[0].segments
    raise_ = next(g for g in segments if g.label == "raise")
    carry = next(g for g in segments if g.label == "carry")
    assert not any(g.label == "pull" for g in segments)
    assert raise_.end.frame == "world" and raise_.end.point[0] == pytest.approx(grip.end.point[0])
    most = pull_accel(hold.mass) * (raise_.t1 - raise_.t0) ** 2 * math.sqrt(3.0) / 10.0
    assert 0.0 < 0.35 - raise_.end.point[1] <= most + 1e-12
    at_raise = plan.trunk_reference_at(raise_.t1)
    start = np.array(raise_.end.point) - at_raise.position  # the trunk faces +y there
    start_in_trunk = (start[1], -start[0], start[2])
    moved = math.dist(start_in_trunk, carry.end.point)
    assert carry.t0 == raise_.t1 and carry.t1 > pick.end
    assert carry.t1 == pytest.approx(raise_.t1 + rest_to_rest(moved, hold.mass), abs=1e-9)
    pull = carry
    assert pull.t1 < plan.tasks[3].start
    st = plan.trunk_reference_at(pull.t1)
    ht = plan.hand_targets_at(pull.t1, st.position, st.yaw)
    c, s = math.cos(st.yaw), math.sin(st.yaw)
    local_l = np.array(
        [
            c * (ht.p_L_world[0] - st.position[0]) + s * (ht.p_L_world[1] - st.position[1]),
            -s * (ht.p_L_world[0] - st.position[0]) + c * (ht.p_L_world[1] - st.position[1]),
            ht.p_L_world[2] - st.position[2],
        ]
    )
    ahead = TRUNK_FRONT + 0.10 + CARRY_IN_GAP
    assert local_l == pytest.approx(
        [ahead, hold.half_width - GRASP_SQUEEZE, CARRY_HEIGHT + GRASP_ABOVE_CENTRE], abs=1e-12
    )
    # and it stays there: no settling out to CARRY_FORWARD before the drop
    assert not any(g.label == "settle" for g in plan.manipulation.tracks[0].segments)
    assert plan.hand_active("L", pick.start + 0.01)
    assert plan.hand_active("R", 0.5 * (pick.end + plan.tasks[3].start))  # carrying


def test_throw_reaches_commanded_velocity_at_release() -> None:
    plan = compile_plan(repo_scenario("throw"))
    throw = next(t for t in plan.tasks if t.action == "throw")
    hold = plan.holds[0]
    st = plan.trunk_reference_at(hold.release)
    ht = plan.hand_targets_at(hold.release, st.position, st.yaw, np.zeros(3), 0.0)
    # relative to a still trunk at yaw 0 the hands move at the commanded body velocity
    assert st.yaw == 0.0
    assert ht.v_L_world == pytest.approx(throw.velocity, abs=1e-12)
    assert ht.v_R_world == pytest.approx(throw.velocity, abs=1e-12)


def test_hand_target_arrays_stack_hand_targets_at() -> None:
    plan = compile_plan(repo_scenario("pick-walk-drop"))
    for t in np.linspace(0.0, plan.t_end, 37).tolist():
        pose = ([0.1, -0.2, 0.6], 0.3, [0.2, 0.1, 0.0], 0.4)
        want = plan.hand_targets_at(t, *pose)
        pos, vel = plan.hand_target_arrays(t, *pose)
        # The same float arithmetic, stacked differently.
        np.testing.assert_array_equal(pos, want.positions)
        np.testing.assert_array_equal(vel, want.velocities)


@pytest.mark.parametrize("name", ["pick-walk-drop", "throw", "package-transfer"])
def test_hand_target_accelerations_are_the_derivative_of_their_velocities(name: str) -> None:
    """The hands' feed-forward (`HandTrack.acceleration`) against a central difference of the
    target velocity, with the trunk moving at a constant velocity and yaw rate (what the
    feed-forward assumes): h = 1e-5 s leaves an O(h^2 jerk') truncation error and an
    O(eps |v| / h) rounding error, both far below the 1e-4 m/s^2 + 1e-5 relative allowed.
    Times within 2h of a segment's ends are skipped (the acceleration of a "world" to "trunk"
    blend is continuous there, but a difference across a boundary mixes two segments)."""
    plan = compile_plan(repo_scenario(name))
    base0, v_b, yaw0, w_b = np.array([0.1, -0.2, 0.6]), np.array([0.2, -0.1, 0.0]), 0.3, 0.7
    h = 1e-5
    bounds = np.array(
        [b for tr in plan.manipulation.tracks for g in tr.segments for b in (g.t0, g.t1)]
    )

    def velocities(t: float) -> np.ndarray:
        return plan.hand_target_arrays(t, base0 + v_b * t, yaw0 + w_b * t, v_b, w_b)[1]

    checked = 0
    for t in np.linspace(0.0, plan.t_end, 401).tolist():
        if np.min(np.abs(bounds - t)) < 2 * h:
            continue
        acc = plan.hand_target_accelerations(t, base0 + v_b * t, yaw0 + w_b * t, v_b, w_b)
        fd = (velocities(t + h) - velocities(t - h)) / (2 * h)
        np.testing.assert_allclose(acc, fd, rtol=1e-5, atol=1e-4)
        checked += 1
    assert checked > 350
