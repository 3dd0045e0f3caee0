"""Issue 14's H1 package transfer and pick-walk-drop, closed loop in MuJoCo, asserted from the
simulation state: scenarios/h1-package-transfer.yaml holds the paper's result in kind
(dynamic at least 1.0 s sooner than quasi-static with a smaller pick-to-drop yaw difference,
both place the package, neither falls), scenarios/h1-pick-walk-drop.yaml places its box, and
a pick during a right turn keeps its parcel level (tests/data/h1-pick-during-right-turn.yaml),
a box pulled in from full reach keeps the elbows on their nominal side
(tests/data/h1-walk-carry-pull-in.yaml), and hands that reach past a high conveyor leave the
parcel where it rests until they close on it (tests/data/h1-pick-past-a-high-conveyor.yaml).
About 70 s of wall time on two cores."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from locoplan.compare import compare_scenario
from locoplan.log.reader import read_log
from locoplan.robot.description import load_robot_description
from locoplan.scenario import load_scenario_file
from locoplan.sim.run import RunOptions, run_scenario

pytestmark = pytest.mark.closed_loop

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
MIN_TIME_SAVED = 1.0  # s, the "at least 1.0 s sooner"


def test_h1_package_transfer_dynamic_is_sooner_with_less_yaw(tmp_path: Path) -> None:
    loaded = load_scenario_file(SCENARIOS / "h1-package-transfer.yaml")
    c = compare_scenario(loaded.scenario, loaded.text, tmp_path, jobs=2)
    assert not c.broke
    qs, dyn = c.outcome("quasi-static").metrics, c.outcome("dynamic").metrics
    assert qs is not None and dyn is not None
    for m in (qs, dyn):
        assert m["scenario"] == "h1-package-transfer"
        assert not m["fell"] and m["completed"]
        assert m["objects"]["package"]["on"] == "conveyor"
        assert m["peak_torque_ratio"] <= 1.0
    # Measured 2026-12-04: 5.33 against 3.93 s, 89.4 against 12.1 deg.
    assert qs["completion_time"] - dyn["completion_time"] >= MIN_TIME_SAVED
    assert dyn["yaw_difference_deg"] < qs["yaw_difference_deg"]


def test_h1_picks_walks_and_places_a_box(tmp_path: Path) -> None:
    desc = load_robot_description("h1")
    loaded = load_scenario_file(SCENARIOS / "h1-pick-walk-drop.yaml")
    scenario = loaded.scenario
    box, platform = scenario.objects["box"], scenario.fixtures["platform"]
    result = run_scenario(scenario, loaded.text, RunOptions(out_dir=tmp_path))
    rec = result.record
    pos = np.asarray(rec.base_position)  # the pelvis, every 10 ms
    assert rec.sim_time >= scenario.end_time - 1e-6
    assert not result.metrics["fell"]
    # Upright throughout: the pelvis within 5 cm of its nominal height, roll and pitch under
    # 5 deg (HECTOR's walk tolerances).
    assert np.max(np.abs(pos[:, 2] - desc.base_height_nominal)) < 0.05
    assert np.max(np.abs(np.degrees(np.asarray(rec.base_rpy)[:, :2]))) < 5.0
    # Walked the 0.6 m along +x.
    assert pos[-1, 0] == pytest.approx(0.6, abs=0.05)
    # The box rests on the platform: centre at its top plus half the box (1 cm for contact),
    # inside its footprint, no longer held.
    end = np.asarray(rec.object_positions["box"])[-1]
    assert abs(end[2] - (platform.size[2] + box.size[2] / 2.0)) < 0.01
    assert abs(end[0] - platform.position[0]) < platform.size[0] / 2.0
    assert abs(end[1] - platform.position[1]) < platform.size[1] / 2.0
    assert "box" not in rec.held_at_end
    assert result.metrics["peak_torque_ratio"] <= 1.0
    assert result.metrics["passed"]


def test_h1_pick_during_a_right_turn_holds_the_parcel_level(tmp_path: Path) -> None:
    """A pick during a 152.6 deg right turn (H1 envelope seed 33331, transfer-052): before the
    reach went round the parcel's near corner, the right hand met that corner, the grasp
    closed there and the parcel turned 60-80 deg in the hands and ended on its side on the
    belt. Now it stays within 25 deg of level in the hands and rests upright on the conveyor.
    In the hold it leans 9-12 deg (its grip off its centre, the palm bond at its friction cap)
    and the loaded turns swing it to 19-21 deg: measured 19.x with the hands at kp 400 on their
    way to the grasp, 20.5 at kp 1500 (robots/h1/robot.yaml `hand_approach_kp`; a palm bond of
    50 rad/s instead of 20 swung it to 28, the lean the same: the cap, not the spring, sets
    it). 25 deg keeps room over that and far below the 60-80 deg of a corner grasp."""
    loaded = load_scenario_file(Path(__file__).parent / "data" / "h1-pick-during-right-turn.yaml")
    scenario = loaded.scenario
    result = run_scenario(scenario, loaded.text, RunOptions(out_dir=tmp_path))
    assert not result.metrics["fell"]
    (hold,) = result.plan.holds
    # The parcel's attitude from the log's simulator state (its free joint's quaternion, w x
    # y z, last in /sim/qpos): the angle between its z axis and the vertical.
    assert result.log_path is not None
    states = list(read_log(result.log_path).messages("/sim/qpos"))
    t = np.array([s[0] for s in states])
    quat = np.array([s[1]["qpos"][-4:] for s in states])
    tilt = np.degrees(np.arccos(np.clip(1.0 - 2.0 * (quat[:, 1] ** 2 + quat[:, 2] ** 2), -1, 1)))
    held = (t > hold.lift) & (t < hold.release)
    assert np.count_nonzero(held) > 100
    assert np.max(tilt[held]) < 25.0
    assert tilt[-1] < 5.0
    assert result.metrics["objects"]["parcel"]["on"] == "conveyor"
    assert result.metrics["passed"]


def test_h1_pull_in_keeps_the_elbows_on_their_side(tmp_path: Path) -> None:
    """A 2.2 kg box pulled in after its pick and carried through a 71 deg turn and a 1.1 m
    walk (H1 envelope seed 40009, walk-carry-002): the hands start the pull-in near full
    reach. Before the arms' working range (`locoplan.robot.arm_range`) both elbows went
    through the straight arm (1.48 rad) and on to their 2.61 rad stop, the hands stayed
    10-20 cm from their targets with the shoulder rolls saturated, and the robot fell at 3.4
    s. Now the elbows stay on their nominal side and the box is placed."""
    loaded = load_scenario_file(Path(__file__).parent / "data" / "h1-walk-carry-pull-in.yaml")
    scenario = loaded.scenario
    result = run_scenario(scenario, loaded.text, RunOptions(out_dir=tmp_path))
    assert not result.metrics["fell"]
    assert result.log_path is not None
    elbows = [
        j.position
        for _, m in read_log(result.log_path).messages("/joint_states")
        for j in m.joints
        if j.name.endswith("elbow")
    ]
    assert len(elbows) > 1000
    # Never past the straight arm (1.48 rad); measured at most 1.25 rad.
    assert max(elbows) < 1.45
    assert result.metrics["objects"]["box"]["on"] == "platform"
    assert result.metrics["peak_torque_ratio"] <= 1.0
    assert result.metrics["passed"]


def test_h1_hands_reaching_past_a_high_conveyor_leave_the_parcel_in_place(
    tmp_path: Path,
) -> None:
    """H1 turns 143 deg past a conveyor at its tucked hands' height and picks during the turn
    (H1 envelope seed 48027, transfer-033). Before the hand paths were ranked with the
    next-nearest obstacle deciding a tie (`Clearance.better_than`), the left hand's reach went
    through the parcel: it pushed the parcel 3.7 cm along the table, the grasp closed 4.2 cm
    wide, the parcel rode tilted and fell off the conveyor. Now the parcel stays within 1 cm
    of where it rests until the grasp closes (measured: it does not move) and ends on the
    conveyor."""
    path = Path(__file__).parent / "data" / "h1-pick-past-a-high-conveyor.yaml"
    loaded = load_scenario_file(path)
    scenario = loaded.scenario
    result = run_scenario(scenario, loaded.text, RunOptions(out_dir=tmp_path))
    assert not result.metrics["fell"]
    (hold,) = result.plan.holds
    rec = result.record
    t = np.asarray(rec.t)
    p_parcel = np.asarray(rec.object_positions["parcel"])
    before = t < hold.grasp
    moved = np.hypot(*(p_parcel[before, :2] - p_parcel[0, :2]).T)
    assert np.max(moved) < 0.01
    assert result.metrics["objects"]["parcel"]["on"] == "conveyor"
    assert result.metrics["passed"]
