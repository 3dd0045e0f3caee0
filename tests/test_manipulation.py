"""Loco-manipulation in MuJoCo, asserted from the simulation state (the object's body pose,
the trunk's free joint, the applied torques). What is not here yet is listed in the README's
results table and in CHANGELOG.md: walking or turning with a load, drops and throws that hit
their targets, and the paper's 14 kg."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from locoplan.scenario import load_scenario, load_scenario_file
from locoplan.sim.robot_plan import compile_robot_plan
from locoplan.sim.run import RunOptions, RunResult, run_scenario

pytestmark = pytest.mark.closed_loop

ROOT = Path(__file__).resolve().parents[1]


def _run(tmp_path: Path, path: Path, **options: object) -> RunResult:
    loaded = load_scenario_file(path)
    return run_scenario(loaded.scenario, loaded.text, RunOptions(out_dir=tmp_path, **options))  # type: ignore[arg-type]


@pytest.mark.parametrize("model", ["external-force", "combined"])
def test_picks_and_holds_five_kilograms(tmp_path: Path, model: str) -> None:
    result = _run(tmp_path, ROOT / "scenarios" / "model-comparison.yaml", model=model)
    rec = result.record
    block = np.asarray(rec.object_positions["block"])
    t = np.asarray(rec.t)
    assert not result.metrics["fell"]
    assert result.metrics["peak_torque_ratio"] <= 1.0
    # Lifted off the table (its centre starts at 0.55 m) and still in the hands 4 s later.
    after = t > 3.0
    assert np.all(block[after, 2] > 0.55 + 0.02)
    assert "block" in rec.held_at_end
    assert result.metrics["completed"]
    # The trunk leans back over the feet (the combined CoM stays over the support).
    base_x = np.asarray(rec.base_position)[after, 0]
    assert np.all(base_x < -0.02)


def test_holds_ten_kilograms_standing(tmp_path: Path) -> None:
    text = (ROOT / "scenarios" / "standing-load.yaml").read_text()
    path = tmp_path / "ten.yaml"
    path.write_text(
        text.replace("mass: 14.0", "mass: 10.0").replace("name: standing-load", "name: ten")
    )
    result = _run(tmp_path, path)
    rec = result.record
    block = np.asarray(rec.object_positions["block"])
    t = np.asarray(rec.t)
    assert not result.metrics["fell"]
    assert result.metrics["peak_torque_ratio"] <= 1.0
    assert result.metrics["torque_clips"] == 0
    # Held for the whole final stand (5 s) above its start height.
    hold = (t > 2.6) & (t < 7.5)
    assert np.all(block[hold, 2] > 0.57)
    assert "block" in rec.held_at_end


def test_holds_fourteen_kilograms_standing(tmp_path: Path) -> None:
    # The paper's 82 % of body mass. The margins are thin on this robot (peak hip-pitch
    # torque ratio about 0.95-0.99), which is why the load comes on over a full second.
    # Its lift balances only with the grasp tolerance, so the pick starts with a step nearer
    # (tests/test_step_in.py) and ends that much later: held from the pick's planned end.
    result = _run(tmp_path, ROOT / "scenarios" / "standing-load.yaml")
    rec = result.record
    block = np.asarray(rec.object_positions["block"])
    t = np.asarray(rec.t)
    assert not result.metrics["fell"]
    assert result.metrics["peak_torque_ratio"] <= 1.0
    assert result.metrics["torque_clips"] == 0
    plan = compile_robot_plan(load_scenario(ROOT / "scenarios" / "standing-load.yaml"))
    pick_end = next(task.end for task in plan.tasks if task.action == "pick")
    assert pick_end < 3.5
    hold = (t > pick_end) & (t < 7.5)  # the rest of the final stand
    # Off the table (its centre rests at 0.55 m): 1 cm of clearance is enough to know the
    # table carries none of it; the arms lift a 14 kg block only 2-4 cm on this robot.
    assert np.all(block[hold, 2] > 0.55 + 0.01)
    assert "block" in rec.held_at_end
    assert result.metrics["objects"]["block"]["held"]


def test_pick_walk_drop_places_the_box_within_the_torque_limits(tmp_path: Path) -> None:
    result = _run(tmp_path, ROOT / "scenarios" / "pick-walk-drop.yaml")
    rec = result.record
    box = np.asarray(rec.object_positions["box"])
    assert not result.metrics["fell"]
    # Carried 0.5 m or more (horizontally, start to end) and resting on its platform.
    assert np.linalg.norm(box[-1, :2] - box[0, :2]) >= 0.5
    assert result.metrics["objects"]["box"]["on"] == "platform"
    # Every expectation of the script holds, max_torque_ratio included: where the paper's
    # WBC QP has no solution in the loaded turn, the joint-relaxed QP keeps the torques
    # within their limits (no clip at all).
    assert result.metrics["passed"], result.metrics["expectations"]
    assert result.metrics["torque_clips"] == 0


def test_throw_lands_near_the_ballistic_prediction(tmp_path: Path) -> None:
    result = _run(tmp_path, ROOT / "scenarios" / "throw.yaml")
    rec = result.record
    assert not result.metrics["fell"]
    assert result.metrics["peak_torque_ratio"] <= 1.0
    kinds = [(k, o) for _, k, o in rec.grasp_events]
    assert ("grasp", "ball") in kinds and ("release", "ball") in kinds
    assert "ball" not in rec.held_at_end
    # Where the ball first comes down to the floor (centre at its radius, 0.10 m), against
    # the plan's ballistic landing point from the commanded release velocity. Samples are
    # 10 ms apart, about 3 cm of flight: well inside the 15 cm.
    t_release = next(t for t, k, o in rec.grasp_events if k == "release" and o == "ball")
    t = np.asarray(rec.t)
    ball = np.asarray(rec.object_positions["ball"])
    down = np.nonzero((t > t_release + 0.05) & (ball[:, 2] <= 0.10 + 0.01))[0]
    assert down.size, "the ball never came down"
    landing = ball[down[0], :2]
    target = result.plan.object_target("ball")
    assert target.position is not None
    assert np.linalg.norm(landing - np.asarray(target.position)[:2]) < 0.15


def test_out_of_reach_pick_is_refused_before_simulating(tmp_path: Path) -> None:
    """A box 0.9 m away: the plan's grasp reach check refuses the pick (exit 2) with where,
    how far out of reach and what would make it feasible, and nothing is simulated."""
    import subprocess
    import sys

    text = """version: 1
name: too-far
objects:
  box: {shape: box, size: [0.2, 0.2, 0.15], mass: 2.0, position: [0.9, 0.0, 0.545]}
fixtures:
  table: {kind: table, position: [0.9, 0.0, 0.0], size: [0.4, 0.4, 0.47]}
tasks:
  - {action: pick, object: box, start: 0.2, duration: 1.0}
end: 2.0
"""
    path = tmp_path / "too-far.yaml"
    path.write_text(text)
    res = subprocess.run(
        [sys.executable, "-m", "locoplan.cli", "run", str(path), "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert res.returncode == 2, res.stdout + res.stderr
    assert "Traceback" not in res.stdout + res.stderr
    message = " ".join((res.stdout + res.stderr).split())
    assert "too-far.yaml:8:5" in message
    assert "infeasible (reach)" in message
    assert "place the object nearer the robot" in message
    assert not list(tmp_path.glob("*.mcap"))


HEAVY_FAST_THROW = """
version: 1
name: heavy-fast-throw
gait: {period: 0.43, swing: 0.17}
objects:
  ball: {shape: sphere, size: [0.096], mass: 1.48, position: [0.332, 0.0, 0.635]}
fixtures:
  table: {kind: table, position: [0.494, 0.0, 0.0], size: [0.439, 0.497, 0.539], yaw: 0.0}
tasks:
  - {action: pick, object: ball, start: 0.5, duration: 1.38}
  - {action: throw, object: ball, velocity: [1.38, 0.14, 1.26], start: 2.8, duration: 1.32}
end: 5.12
"""


def test_a_heavy_fast_throw_keeps_the_feet_down(tmp_path: Path) -> None:
    """1.48 kg thrown at 1.9 m/s (envelope seed 16180, throw-000): at the release the hand
    targets once went back at once to the plan's, 2-6 cm closer together than the ball held
    the hands; both shoulder rolls jumped to 0.84 of their limit, a foot came off the ground
    and the robot fell 1.3 s later. With the release eased (`_released_pair_targets`) it
    stays up within the torque limits, the trunk within 5 cm of where it started, and the
    ball comes down within the issue's 15 cm of its ballistic point."""
    path = tmp_path / "heavy-fast-throw.yaml"
    path.write_text(HEAVY_FAST_THROW)
    result = _run(tmp_path, path)
    rec = result.record
    assert not result.metrics["fell"]
    assert result.metrics["peak_torque_ratio"] <= 1.0
    base = np.asarray(result.metrics["final_base"]["position"])
    assert np.linalg.norm(base[:2]) < 0.05
    t_release = next(t for t, k, o in rec.grasp_events if k == "release" and o == "ball")
    t = np.asarray(rec.t)
    ball = np.asarray(rec.object_positions["ball"])
    down = np.nonzero((t > t_release + 0.05) & (ball[:, 2] <= 0.096 + 0.01))[0]
    assert down.size, "the ball never came down"
    target = result.plan.object_target("ball")
    assert target.position is not None
    assert np.linalg.norm(ball[down[0], :2] - np.asarray(target.position)[:2]) < 0.15


# Envelope seed 50021's dynamic transfer-001: the parcel (5.89 kg, 0.37 m ahead) is picked at
# the end of a 60 deg turn and the robot turns back 112 deg 0.3 s after its weight came on.
HEAVY_TURN_BACK = """
version: 1
name: heavy-turn-back
gait: {period: 0.44, swing: 0.18}
objects:
  parcel: {shape: box, size: [0.167, 0.238, 0.212], mass: 5.89,
           position: [0.177, 0.307, 0.608], yaw: 60.1}
fixtures:
  table: {kind: table, position: [0.275, 0.478, 0.0], size: [0.532, 0.423, 0.502], yaw: 60.1}
  platform: {kind: platform, position: [0.218, -0.282, 0.0], size: [0.335, 0.326, 0.49], yaw: -52.3}
tasks:
  - {action: turn, angle: 60.1, start: 0.0, duration: 1.38}
  - {action: pick, object: parcel, start: 0.77, duration: 1.02}
  - {action: turn, angle: -112.4, start: 1.79, duration: 2.27}
  - {action: drop, object: parcel, onto: platform, start: 3.98, duration: 0.82}
end: 5.8
"""


def test_a_heavy_parcel_picked_before_a_turn_back_keeps_the_trunk_on_its_path(
    tmp_path: Path,
) -> None:
    """The whole held-load lean (`LocoManipulationController._lean_weights`): with half of it
    the parcel's weight came on with the combined CoM 1-3 cm inside the toes, the pull-in's
    reaction ran the CoM forward (0.2-0.5 m/s), the turn's steps walked the trunk 0.3-0.5 m off
    its path into the table and the robot fell. Now the trunk stays within 0.1 m of the plan's
    trunk path (6 cm measured) and the parcel ends on its platform."""
    loaded = load_scenario_file(Path("heavy-turn-back.yaml"), HEAVY_TURN_BACK)
    result = run_scenario(loaded.scenario, loaded.text, RunOptions(out_dir=tmp_path))
    assert not result.metrics["fell"]
    assert result.metrics["peak_torque_ratio"] <= 1.0
    assert result.metrics["objects"]["parcel"]["on"] == "platform"
    rec = result.record
    base = np.asarray(rec.base_position)
    ref = np.array([result.plan.trunk_reference_at(float(t)).position for t in rec.t])
    assert np.max(np.hypot(*(base[:, :2] - ref[:, :2]).T)) < 0.1


def _lurch_after_lift(result: RunResult, yaw_deg: float) -> float:
    """How far (m) the trunk moves along the heading `yaw_deg` (the robot's, at its one pick)
    in the 0.55 s after the planned lift-off, beyond where it stood then (from the MuJoCo
    state the run recorded)."""
    (hold,) = result.plan.holds
    t = np.asarray(result.record.t)
    yaw = np.radians(yaw_deg)
    forward = np.asarray(result.record.base_position)[:, :2] @ np.array([np.cos(yaw), np.sin(yaw)])
    before = forward[t <= hold.lift][-1]
    window = (t >= hold.lift) & (t <= hold.lift + 0.55)
    return float(forward[window].max() - before)


def test_heavy_pick_is_lifted_on_time_and_the_turn_after_it_holds(tmp_path: Path) -> None:
    """A 7.97 kg box 0.30 m ahead, picked 0.09 s before a loaded turn (envelope seed 58021,
    walk-carry-019). The WBC feeds the box's whole weight forward at the hands from the
    planned lift-off (`LocoManipulationController._lift_mass`), so the box leaves its table
    as the raise begins, not when the hands' tracking error has built the force: before,
    it left 0.18 s late, the hands whipped it in to catch up with their path (0.5 m/s) and
    the reaction ran the trunk 12.9 cm forward in the 0.55 s before the turn (at 0.53 m/s),
    the combined centre of mass past the toes; the robot fell in the turn. Now the trunk
    moves 1.7 cm; asserted under 5 cm (the toe is 9 cm ahead of the ankle, and the robot's
    own CoM stands 3 cm behind it at the lift-off), then the whole task: no fall, torques
    within the limits, the box placed on its platform."""
    result = _run(tmp_path, ROOT / "tests" / "data" / "heavy-pick-then-turn.yaml")
    assert _lurch_after_lift(result, 75.1) < 0.05
    assert not result.metrics["fell"]
    assert result.metrics["peak_torque_ratio"] <= 1.0
    assert result.passed


def test_a_heavy_box_far_out_on_a_low_table_is_gripped_with_room_and_raised_first(
    tmp_path: Path,
) -> None:
    """A 7.62 kg box 0.35 m ahead on a 0.40 m table, a loaded turn 0.05 s after the pick
    (envelope seed 62021, walk-carry-027). Gripped at its centre, the grip points were at the
    arms' full stretch (elbows on their joint limit), the lean back for the load dragged the
    box across its table through the straight arms (up to 146 N at the hands on a sister
    script), and the reaction ran the trunk 21.5 cm towards the table within 0.55 s of the
    lift-off; the robot fell. Gripped GRIP_BEHIND_CENTRE nearer (room for the arms) and raised
    straight up before it is pulled in (RAISE_UP_SHARE), the trunk moves 4.6 cm; asserted
    under 8 cm, then the whole task."""
    result = _run(tmp_path, ROOT / "tests" / "data" / "heavy-far-low-pick.yaml")
    (hold,) = result.plan.holds
    assert hold.grip_behind == pytest.approx(0.03)
    assert _lurch_after_lift(result, -74.2) < 0.08
    assert not result.metrics["fell"]
    assert result.metrics["peak_torque_ratio"] <= 1.0
    assert result.passed


def test_a_reach_over_a_platform_during_a_turn_places_the_parcel(tmp_path: Path) -> None:
    """tests/data/reach-over-a-platform.yaml (HECTOR envelope seed 71021, transfer-028): the
    right hand, planned into the platform it passes while the robot turns to the table, met
    it at 1.2 s and shoved the trunk 10 cm off its turn; the grasp closed 10 cm off the
    parcel's centre, the parcel hung 20-30 deg and snagged the platform's corner on the way
    back, and was not placed. Going over the platform, the trunk stays within 5 cm of its
    turn-in-place point until the grasp (measured 2 cm; 12 cm before), nothing falls and
    the parcel is placed."""
    loaded = load_scenario_file(Path(__file__).parent / "data" / "reach-over-a-platform.yaml")
    result = run_scenario(loaded.scenario, loaded.text, RunOptions(out_dir=tmp_path))
    (hold,) = result.plan.holds
    t = np.asarray(result.record.t)
    base = np.asarray(result.record.base_position)
    before = t < hold.grasp
    assert np.max(np.hypot(base[before, 0], base[before, 1])) < 0.05
    assert not result.metrics["fell"]
    assert result.metrics["objects"]["parcel"]["on"] == "platform"
