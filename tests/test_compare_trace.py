"""Run traces: the series the plots use, built from a RunRecord and the plan (no simulation:
a record filled with the plan's own reference)."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
from compare_fixtures import repo_scenario_text, synthetic_trace

from locoplan.compare import FixtureOutline, fixture_outlines
from locoplan.compare.trace import PLAN_SAMPLE, pick_drop_pair
from locoplan.plan import compile_plan


def test_pick_drop_pair_is_the_metrics_rule() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    # Starts written in the script (dynamic) and after the 0.7 s / 1.4 s quasi-static shifts.
    pick, drop, kind = pick_drop_pair(compile_plan(scenario, "dynamic"))  # type: ignore[misc]
    assert (pick, drop, kind) == (pytest.approx(0.9), pytest.approx(2.8), "drop")
    pick, drop, kind = pick_drop_pair(compile_plan(scenario, "quasi-static"))  # type: ignore[misc]
    assert (pick, drop, kind) == (pytest.approx(1.6), pytest.approx(4.2), "drop")
    throw, _ = repo_scenario_text("throw")
    assert pick_drop_pair(compile_plan(throw))[2] == "throw"  # type: ignore[index]
    turn, _ = repo_scenario_text("turn")
    assert pick_drop_pair(compile_plan(turn)) is None


def test_trace_follows_the_record_and_the_plan() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    tr = synthetic_trace(scenario, "dynamic", "dynamic")
    n = tr.t.size
    assert tr.base_position.shape == (n, 3) and tr.base_rpy.shape == (n, 3)
    assert tr.joint_torque.shape == (n, 16)
    assert tr.leg_joints[0] == ("L_hip_yaw", "L_hip_roll", "L_hip_pitch", "L_knee", "L_ankle")
    # The plan grid covers the whole plan at the record's period.
    assert tr.t_plan[-1] == pytest.approx(tr.t_end, abs=PLAN_SAMPLE / 2)
    assert tr.feet_stance.shape == (tr.t_plan.size, 2)
    # Hands touch the package from the grasp to the release, the weight is held from the lift.
    plan = compile_plan(scenario, "dynamic")
    hold = plan.holds[0]
    held_times = tr.t_plan[tr.object_held]
    assert held_times[0] == pytest.approx(hold.lift, abs=PLAN_SAMPLE)
    assert held_times[-1] == pytest.approx(hold.release, abs=PLAN_SAMPLE)
    assert tr.hands_contact[:, 0].sum() > tr.object_held.sum()  # grasp comes before lift
    # The synthetic record puts the held package on its planned carry pose, which is
    # higher than the table: "lifted" follows the hold.
    assert tr.object_lifted["package"].any()
    lifted_t = tr.t[tr.object_lifted["package"]]
    assert lifted_t[0] >= hold.lift - 1e-9
    assert tr.object_targets["package"][2] == pytest.approx(0.545, abs=1e-3)


def test_yaw_difference_of_the_plan() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    qs = synthetic_trace(scenario, "quasi-static", "quasi-static")
    dyn = synthetic_trace(scenario, "dynamic", "dynamic")
    # Quasi-static: the whole first turn is done at the pick start and the second one starts
    # at the drop: 90 deg. Dynamic: "about 17 deg" (scenario description): both turns are
    # 0.5625 of their way in time at the pick and drop starts, which the cruise profile (ramps
    # of 1/3) turns by 1.5 x (0.5625 - 1/6) = 0.594 of 90 deg each way, a difference of
    # 16.875 deg. Interpolation of 10 ms samples of a smooth profile: 0.5 deg.
    assert qs.yaw_difference_deg == pytest.approx(90.0, abs=0.5)
    assert dyn.yaw_difference_deg == pytest.approx(16.875, abs=0.5)


def test_no_yaw_difference_when_the_drop_is_not_reached() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    tr = synthetic_trace(scenario, "quasi-static", "quasi-static", fall_at=3.0)
    assert tr.fall_time == 3.0
    assert tr.yaw_difference_deg is None
    assert tr.t_plan[-1] == pytest.approx(tr.t_end, abs=PLAN_SAMPLE / 2)  # plan goes on


def test_trace_crosses_process_boundaries() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    tr = synthetic_trace(scenario, "dynamic", "dynamic")
    back = pickle.loads(pickle.dumps(tr))
    np.testing.assert_array_equal(back.t, tr.t)
    assert back.tasks == tr.tasks


def test_fixture_outline_corners() -> None:
    # A 1.2 x 0.35 conveyor turned 90 deg spans 0.35 m in x and 1.2 m in y.
    f = FixtureOutline("c", "conveyor", (0.4, 0.0), (1.2, 0.35), math.radians(90), 0.47)
    c = f.corners()
    assert c.shape == (5, 2)
    np.testing.assert_allclose(c[0], c[-1])
    np.testing.assert_allclose(np.ptp(c[:, 0]), 0.35, atol=1e-12)
    np.testing.assert_allclose(np.ptp(c[:, 1]), 1.2, atol=1e-12)
    np.testing.assert_allclose(c[:4].mean(axis=0), [0.4, 0.0], atol=1e-12)


def test_fixture_outlines_of_a_scenario() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    out = {f.name: f for f in fixture_outlines(scenario)}
    assert set(out) == {"table", "conveyor"}
    assert out["conveyor"].yaw == pytest.approx(math.pi / 2)
    assert out["table"].top == pytest.approx(0.47)
