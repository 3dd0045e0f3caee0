"""Foot contact schedule (locoplan.plan.gait): alternation, whole cycles, flags."""

from __future__ import annotations

import math

import numpy as np
import pytest
from plan_fixtures import repo_scenario, scenario_files, scenario_from_text

from locoplan.plan import PlanError, compile_plan
from locoplan.plan.constants import GAIT_MIN_DOUBLE_SUPPORT
from locoplan.plan.gait import start_lead
from locoplan.scenario import load_scenario
from locoplan.sim.robot_plan import compile_robot_plan

TIME_TOL = 1e-9  # float rounding of sums of a few decimal times


@pytest.mark.parametrize("path", scenario_files(), ids=lambda p: p.stem)
@pytest.mark.parametrize("strategy", ["dynamic", "quasi-static"])
def test_feet_never_both_swing_and_swings_cover_locomotion(path, strategy) -> None:
    scenario = load_scenario(path)
    plan = compile_robot_plan(scenario, strategy)
    times = np.linspace(-0.5, plan.t_end + 0.5, 20001)
    flags = plan.contact_flags(times)
    assert flags.any(axis=1).all(), "both feet in swing at once"
    loco = [t for t in plan.tasks if t.kind == "locomotion"]
    inside = np.zeros(times.shape, dtype=bool)
    for task in loco:
        inside |= (times >= task.start) & (times < task.end)
        # every swing of the task lies inside it, and both feet swing at least once
        for foot in ("L", "R"):
            swings = [
                (a, b)
                for a, b in plan.swing_intervals(foot)
                if task.start - TIME_TOL <= a < task.end
            ]
            assert swings, (task, foot)
            block = next(b for b in plan.contacts.blocks if b.task_index == task.index)
            if foot == "L":  # the left foot lifts off as the gait block starts
                assert swings[0][0] == pytest.approx(block.start, abs=TIME_TOL)
                lead = start_lead(task, scenario.gait.period, plan.geometry.settle_time)
                assert block.start == pytest.approx(task.start + lead, abs=TIME_TOL)
            else:  # the right foot's last swing is in the task's last half cycle
                assert swings[-1][0] == pytest.approx(task.end - block.period / 2, abs=TIME_TOL)
            assert all(b <= task.end - GAIT_MIN_DOUBLE_SUPPORT + TIME_TOL for _, b in swings)
    assert flags[~inside].all(), "a foot swings outside locomotion"
    # stance and swing intervals are complementary over [0, t_end]
    for foot in ("L", "R"):
        total = sum(b - a for a, b in plan.stance_intervals(foot)) + sum(
            b - a for a, b in plan.swing_intervals(foot)
        )
        assert total == pytest.approx(plan.t_end, abs=1e-9)


def test_whole_cycles_left_first_and_swing_capped() -> None:
    text = """
version: 1
name: gait
gait: {period: 0.4, swing: 0.19}
tasks:
  - {action: step, start: 1.0, duration: 1.3}
  - {action: turn, angle: 30, start: 2.5, duration: 0.3}
"""
    plan = compile_plan(scenario_from_text(text))
    step, turn = plan.contacts.blocks
    assert step.cycles == 3 and step.period == pytest.approx(1.3 / 3)
    assert step.swing == pytest.approx(0.19)  # 0.19 <= 0.4333 / 2 - 0.02: kept
    assert turn.cycles == 1 and turn.period == pytest.approx(0.3)
    assert turn.swing == pytest.approx(0.15 - GAIT_MIN_DOUBLE_SUPPORT)  # capped
    left = plan.swing_intervals("L")
    right = plan.swing_intervals("R")
    assert left[0] == pytest.approx((1.0, 1.19))
    assert right[0] == pytest.approx((1.0 + step.period / 2, 1.0 + step.period / 2 + 0.19))
    assert len(left) == len(right) == 4


def test_contact_flags_vectorised_equals_scalar() -> None:
    plan = compile_plan(repo_scenario("walk-square"))
    rng = np.random.default_rng(0)
    times = np.concatenate(
        [rng.uniform(-1.0, plan.t_end + 1.0, 3000), np.array(plan.swing_intervals("L")).ravel()]
    )
    flags = plan.contact_flags(times)
    for i, t in enumerate(times):
        assert flags[i, 0] == plan.foot_stance("L", float(t))
        assert flags[i, 1] == plan.foot_stance(1, float(t))
    assert np.array_equal(plan.foot_stance("R", times), flags[:, 1])


def test_swing_phase_and_next_touchdown() -> None:
    plan = compile_plan(repo_scenario("step"))
    a, b = plan.swing_intervals("L")[3]
    mid = 0.5 * (a + b)
    phase = plan.swing_phase("L", mid)
    assert phase is not None
    assert (phase.liftoff, phase.touchdown) == (a, b)
    assert phase.phase == pytest.approx(0.5, abs=1e-12)
    assert plan.swing_phase("L", b) is None  # touchdown instant is stance (half-open swing)
    assert plan.swing_phase("L", a).phase == 0.0
    assert plan.next_touchdown("L", mid) == b
    nxt = plan.swing_intervals("L")[4]
    assert plan.next_touchdown("L", b) == nxt[1]
    assert plan.next_liftoff("L", b) == nxt[0]
    assert plan.stance_start("L", b + 0.01) == b
    first = plan.swing_intervals("L")[0]
    assert first[0] == pytest.approx(0.2)  # the start lead: half of step.yaml's 0.4 s period
    assert plan.stance_start("L", 0.0) is None  # initial stance, shifting the weight
    assert plan.stance_start("L", first[0]) == first[1]  # swinging
    assert plan.stance_start("R", 0.0) is None
    assert plan.next_touchdown("L", plan.t_end) is None
    assert plan.gait_period_at(mid) == pytest.approx(0.4, abs=0.01)


def test_start_lead_shifts_the_weight_before_the_first_liftoff() -> None:
    """A locomotion task at the simulation's start lifts its first foot after the robot's
    pendulum time sqrt(z / g), at most half a gait period later, its cycles (as many as
    without the lead) fitted into what is left; a task starting later (the MPC sees its
    lift-off coming) keeps its start, and a short one keeps half a period per cycle."""
    text = """
version: 1
name: lead
gait: {period: 0.6, swing: 0.25}
tasks:
  - {action: turn, angle: -110, start: 0.0, duration: 3.0}
  - {action: step, start: 3.5, duration: 1.2}
"""
    plan = compile_plan(scenario_from_text(text))
    settle = plan.geometry.settle_time
    assert settle == pytest.approx(math.sqrt(0.6 / 9.81))  # HECTOR's 0.60 m trunk height
    turn, step = plan.contacts.blocks
    assert turn.start == pytest.approx(settle) and turn.end == pytest.approx(3.0)
    assert turn.cycles == 5 and turn.period == pytest.approx((3.0 - settle) / 5)
    assert plan.swing_intervals("L")[0][0] == pytest.approx(settle)
    assert plan.contact_flags(np.linspace(0.0, settle - 1e-6, 50)).all()
    assert step.start == pytest.approx(3.5)  # no lead after 3.5 s of preview
    quick = compile_plan(
        scenario_from_text(text.replace("period: 0.6, swing: 0.25", "period: 0.4, swing: 0.15"))
    )
    assert quick.contacts.blocks[0].start == pytest.approx(0.2)  # half the period
    assert quick.contacts.blocks[0].cycles == round(3.0 / 0.4)
    late = compile_plan(
        scenario_from_text(text.replace("start: 0.0, duration: 3.0", "start: 0.1, duration: 2.9"))
    )
    assert late.contacts.blocks[0].start == pytest.approx(settle)  # waits until settle only
    short = "angle: -20, start: 0.0, duration: 0.35"
    one = compile_plan(
        scenario_from_text(text.replace("angle: -110, start: 0.0, duration: 3.0", short))
    )
    block = one.contacts.blocks[0]
    assert block.cycles == 1 and block.period == pytest.approx(0.3)  # half of 0.6 left
    assert block.start == pytest.approx(0.05)


def test_overlapping_locomotion_is_refused() -> None:
    scenario = repo_scenario("turn")
    # bypass the loader's semantic check to exercise the compiler's own guard
    data = scenario.model_dump()
    data["tasks"].append({"action": "step", "start": 1.0, "duration": 1.0})
    bad = type(scenario).model_validate(data)
    with pytest.raises(PlanError, match="two locomotion tasks"):
        compile_plan(bad)


def test_footholds_follow_trunk_and_end_square() -> None:
    plan = compile_plan(repo_scenario("walk-square"))
    walk = plan.tasks[0]
    x, y, yaw = plan.final_pose
    fh = plan.footholds_at(np.array([0.0, walk.end, plan.t_end]))
    assert fh[0, 0] == pytest.approx([0.0, 0.1, 0.0])
    assert fh[0, 1] == pytest.approx([0.0, -0.1, 0.0])
    # after the first walk both feet stand square beside the trunk, 0.5 m ahead
    assert fh[1, 0] == pytest.approx([0.5, 0.1, 0.0], abs=1e-12)
    assert fh[1, 1] == pytest.approx([0.5, -0.1, 0.0], abs=1e-12)
    assert fh[2, 0] == pytest.approx([x - np.sin(yaw) * 0.1, y + np.cos(yaw) * 0.1, 0.0], abs=1e-9)


def test_stance_starts_is_stance_start_at_every_time() -> None:
    plan = compile_plan(repo_scenario("step"))
    times = np.linspace(-0.1, plan.t_end + 0.1, 997)
    for foot in ("L", "R"):
        got = plan.stance_starts(foot, times)
        for t, g in zip(times.tolist(), got.tolist(), strict=True):
            want = plan.stance_start(foot, t)
            assert (want is None and math.isnan(g)) or want == g
