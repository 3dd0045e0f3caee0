"""locoplan.plan.payload: the static check of a plan's carry and place poses. Refusals through
every command that plans (exit 2, file:line:column, `infeasible (payload)` / `infeasible
(balance)`), the margins `locoplan plan` prints, and no refusal of the repository's scripts or
of the envelope's."""

from __future__ import annotations

import json
import math
import re
import shutil
from pathlib import Path
from typing import Any

import pytest
from plan_fixtures import hold_script, scenario_files, scenario_from_text
from typer.testing import CliRunner

from locoplan.batch.job import Job
from locoplan.batch.worker import execute_job
from locoplan.cli import app
from locoplan.envelope import FAMILIES, generate_suite
from locoplan.plan import Plan, PlanError, compile_plan
from locoplan.plan.compiler import HURRIED_LOADED_TURN_RATE, HURRIED_TURN_RATE
from locoplan.plan.payload import (
    PLACE_SLACK,
    PRE_LEAN_MAX,
    PRE_LEAN_TOL,
    LiftMargin,
    check_payload,
    grasp_reach_limit,
    payload_margins,
    planned_grasp,
    planned_holds,
    pre_lean_room,
)
from locoplan.plan.statics import static_model
from locoplan.scenario import load_scenario, load_scenario_file
from locoplan.sim.robot_plan import compile_robot_plan
from locoplan.sim.run import RunOptions

runner = CliRunner()
ROBOTS = Path(__file__).resolve().parents[1] / "robots"
ENVELOPE_EXAMPLES = Path(__file__).resolve().parent / "data" / "envelope"


# Lines (1-based) of the pick and the drop in hold_script without a robot line; column 5 is
# the task's `{`.
PICK_AT, DROP_AT = "9:5", "11:5"


def _write(tmp_path: Path, text: str, name: str = "hold.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_poses_of_a_plan_are_the_carry_and_the_place_points() -> None:
    # 7 kg: this geometry lifts up to 8 kg (`check_lift`; issue 12's 11 kg is refused); the
    # planner steps nearer first (`compiler._step_in_off_the_tolerance`).
    plan = compile_plan(scenario_from_text(hold_script(7.0)))
    walk = next(t for t in plan.tasks if t.action == "walk")
    step = walk.distance[0] if walk.distance else 0.0
    assert step > 0.0
    # Without a model both carry poses: where the pick leaves the box (as far ahead as it
    # was picked, 0.356 m less the step) and where the hands then settle it in
    # (CARRY_FORWARD, 0.30 m).
    grasp, picked, settled, _ = planned_holds(plan)
    # The grasp pose: the grip points at the lift-off, the block still on its table (mass 0).
    assert grasp.kind == "grasp" and grasp.mass == 0.0
    assert grasp.pose.p_hands_trunk[0][0] == pytest.approx(0.356 - step)
    assert picked.pose.p_hands_trunk[0][0] == pytest.approx(0.356 - step)
    assert settled.pose.p_hands_trunk[0][0] == pytest.approx(0.30)
    holds = planned_holds(plan, static_model("hector"))
    kinds = [(h.kind, h.task_index) for h in holds]
    assert kinds == [("grasp", 1), ("carry", 1), ("place", 3)]
    _, carry, place = holds
    assert carry == picked  # the worse of the two: further ahead
    # Carried standing: gripped at its centre, both hands at the same trunk-frame point
    # ahead, symmetric about the centre line, 0.01 m inside the box's 0.234 m width.
    (xl, yl, zl), (xr, yr, zr) = carry.pose.p_hands_trunk
    assert (xl, zl) == pytest.approx((xr, zr)) and yl == pytest.approx(-yr)
    assert yl == pytest.approx(0.234 / 2 - 0.01)
    # Placed back on the table: the hands at its centre's height in the trunk frame.
    assert place.pose.p_hands_trunk[0][2] == pytest.approx(0.543 - plan.trunk.height, abs=1e-3)
    assert carry.mass == place.mass == 7.0
    assert carry.pose.trunk_height == plan.trunk.height


def test_pre_lean_room_is_how_far_back_the_arms_still_reach_the_grip() -> None:
    """`pre_lean_room`: moving the trunk back from the grasp pose by the room leaves both
    arms reaching their grip points (reach margin >= 0), by one search step more does not;
    a box further out leaves less room, and one at the arms' full stretch none. The plan's
    hold carries it (`ObjectHold.pre_lean`, and the plan JSON)."""
    from dataclasses import replace as dc_replace

    model = static_model("hector")
    rooms = []
    for x in (0.30, 0.356, 0.42):
        # 3 kg: lifted even at the arms' full stretch (6 kg 0.42 m out is refused: `check_lift`).
        text = hold_script(3.0, step_time=False).replace(
            "position: [0.356, 0.0, 0.543]", f"position: [{x}, 0.0, 0.543]"
        )
        plan = compile_plan(scenario_from_text(text))
        grasp = planned_holds(plan)[0]
        room = pre_lean_room(model, grasp.pose)
        (hold,) = plan.holds
        assert hold.pre_lean == room and plan.to_dict()["holds"][0]["pre_lean"] == room
        rooms.append(room)

        def margin(b: float, pose=grasp.pose) -> float:
            pts = tuple((p[0] + b, p[1], p[2]) for p in pose.p_hands_trunk)
            return model.postures.arms(dc_replace(pose, p_hands_trunk=pts))[2]

        if 0.0 < room < PRE_LEAN_MAX:
            assert margin(room) >= 0.0 > margin(room + 2 * PRE_LEAN_TOL), (x, room)
    assert rooms[0] > rooms[1] > rooms[2] == 0.0, rooms


def test_check_refuses_the_carry_pose_at_the_pick() -> None:
    scenario = scenario_from_text(hold_script(30.0))
    with pytest.raises(PlanError) as info:
        compile_plan(scenario)
    exc = info.value
    assert exc.loc == ("tasks", 1) and exc.task_index == 1
    assert exc.message.startswith("infeasible (payload): 30 kg exceeds the ")
    assert "in the carry pose of 'block'" in exc.message
    assert exc.message.endswith("or hold it closer")


def test_check_refuses_the_place_pose_at_the_drop() -> None:
    # The table puts the box back 0.40 m ahead, further than it is carried (0.36 m): a mass
    # between the two poses' limits passes the carry and is refused at the release.
    plan = compile_plan(scenario_from_text(hold_script(1.0)))
    model = static_model("hector")
    margins: dict[str, float] = {}
    for h in planned_holds(plan)[1:]:  # both carry poses (picked and settled) and the place
        limit = model.payload_limit(h.pose)
        margins[h.kind] = min(margins.get(h.kind, limit), limit)
    assert margins["place"] < margins["carry"] - 1.0
    mass = round(0.5 * (margins["place"] + margins["carry"]), 1)
    with pytest.raises(PlanError) as info:
        compile_plan(scenario_from_text(hold_script(mass)))
    exc = info.value
    assert exc.loc == ("tasks", 3)
    assert "in the place pose of 'block' at its release" in exc.message
    assert f"carry at most {int(margins['place'] * 10) / 10:.1f} kg" in exc.message
    assert exc.message.endswith("or place it nearer the robot")


def test_margins_below_the_limit() -> None:
    [grasp, carry, place] = payload_margins(
        compile_plan(scenario_from_text(hold_script(7.0, step_time=False))), "hector"
    )
    assert grasp.hold.kind == "grasp" and grasp.analysis.reach_margin > 0.0
    # Its lift, the trunk leaned back the arms' room and the 3 cm grasp tolerance: inside
    # the toes.
    assert grasp.lift is not None and 0.0 < grasp.lift.margin < 0.02
    for m in (carry, place):
        a = m.analysis
        assert a.balanced and 0.4 < a.torque_ratio < 1.0 and a.joint.endswith("hip_pitch")
        assert 7.0 < a.payload_limit < 25.0
        assert a.com_margin > 0.0
        assert m.lift is None
    row = carry.to_dict()
    assert row["pose"] == "carry" and row["task"] == 1 and row["mass"] == 7.0
    assert set(row) >= {"torque_ratio", "joint", "com_margin", "reach_margin", "payload_limit"}


# A pick that starts early in a long turn (envelope seed 777, transfer-042): at its lift-off
# the trunk still faces 38 deg away from the parcel, whose grip points are then 0.16 m out
# of the arms' reach (in closed loop it missed the grasp by 0.114 m).
EARLY_TURNING_PICK = """version: 1
name: early-turning-pick
gait: {period: 0.37, swing: 0.18}
objects:
  parcel: {shape: box, size: [0.144, 0.224, 0.196], mass: 1.02,
           position: [-0.286, 0.2, 0.644], yaw: 145.1}
fixtures:
  table: {kind: table, position: [-0.417, 0.291, 0.0], size: [0.402, 0.576, 0.546], yaw: 145.1}
  platform: {kind: platform, position: [0.381, 0.1, 0.0], size: [0.316, 0.323, 0.475], yaw: 14.7}
tasks:
  - {action: turn, angle: 145.1, start: 0.0, duration: 3.69}
  - {action: pick, object: parcel, start: %s, duration: 0.87}
  - {action: turn, angle: -130.4, start: 3.69, duration: 2.08}
  - {action: drop, object: parcel, onto: platform, start: 5.66, duration: 0.93}
end: 7.59
"""


def test_grasp_out_of_reach_of_the_planned_trunk_is_refused_with_a_later_start() -> None:
    # The pick starts in the turn's first tenth: even the quickest turn the planner may
    # plan (HURRIED_TURN_RATE) faces the parcel only after the lift-off.
    with pytest.raises(PlanError) as info:
        compile_plan(scenario_from_text(EARLY_TURNING_PICK % "0.30"))
    exc = info.value
    assert exc.loc == ("tasks", 1) and exc.task_index == 1
    assert exc.message.startswith("infeasible (reach): at the lift-off of 'parcel'")
    assert "m beyond the arms' reach" in exc.message
    later = float(exc.message.split("start the pick at ")[1].split(" s")[0])
    assert 0.30 < later < 2.81
    # The advice holds: starting there, the plan reaches its grasp (and is not refused).
    compile_plan(scenario_from_text(EARLY_TURNING_PICK % f"{later:.2f}"))


def test_a_pick_early_in_a_long_turn_hurries_the_turn_to_face_the_object() -> None:
    """A pick in the last half of the turn (inside issue 12's envelope) whose lift-off comes
    before the trunk faces the parcel: the planner ends the turn sooner, within the rate it
    may plan, instead of refusing the script, and says so."""
    scenario = scenario_from_text(EARLY_TURNING_PICK % "1.94")
    plan = compile_plan(scenario)
    written = scenario.tasks[0]
    turn = plan.tasks[0]
    assert turn.action == "turn" and turn.start == 0.0
    amount = math.radians(145.1)
    # Sooner than written, no quicker than the planner's cap, and only as much as needed:
    # the written turn misses the grasp, the hurried one keeps it within the limit.
    assert amount / HURRIED_TURN_RATE - 0.01 <= turn.end < written.duration
    # The turn ends by the lift-off, so the trunk faces the parcel while the hands close.
    grasp = planned_grasp(plan, 1, "hector")
    assert grasp is not None
    lift_off, residual = grasp
    # (durations round up to 0.01 s, as a script writes them)
    assert turn.end <= lift_off + 0.01 and residual <= grasp_reach_limit()
    assert plan.notes == (
        f"the turn by 145 deg from 0.00 s ends at {turn.end:.2f} s instead of 3.69 s so that "
        "the trunk faces 'parcel' at its lift-off",
    )
    assert plan.to_dict()["notes"] == list(plan.notes)
    # Every other task keeps its written times.
    assert [(t.start, t.end) for t in plan.tasks[1:]] == [
        (t.start, t.start + t.duration) for t in scenario.tasks[1:]
    ]


# A pick (right hand) early in a turn, with or without a cup held in the left hand through
# that turn (the cup's pick is the line marked CUP).
TURNING_PICK_WITH_A_CUP = """version: 1
name: two-picks
gait: {period: 0.37, swing: 0.18}
objects:
  cup: {shape: box, size: [0.06, 0.06, 0.08], mass: 0.3, position: [0.27, 0.1, 0.59], yaw: 0}
  parcel: {shape: box, size: [0.08, 0.08, 0.1], mass: 0.5,
           position: [-0.27, 0.15, 0.6], yaw: 145.1}
fixtures:
  shelf: {kind: table, position: [0.4, 0.1, 0.0], size: [0.3, 0.3, 0.55], yaw: 0}
  table: {kind: table, position: [-0.417, 0.291, 0.0], size: [0.402, 0.576, 0.546], yaw: 145.1}
tasks:
  - {action: pick, object: cup, hands: left, start: 0.0, duration: 1.0}  # CUP
  - {action: turn, angle: 145.1, start: 1.0, duration: 3.69}
  - {action: pick, object: parcel, hands: right, start: 2.1, duration: 0.87}
end: 6.0
"""


def test_a_hurried_turn_is_slower_while_another_object_is_held() -> None:
    # Empty-handed, the turn may be hurried to 90 deg/s: 145.1 deg in 1.62 s.
    alone = TURNING_PICK_WITH_A_CUP.replace(
        "  - {action: pick, object: cup, hands: left, start: 0.0, duration: 1.0}  # CUP\n", ""
    )
    plan = compile_plan(scenario_from_text(alone))
    turn = plan.tasks[0]
    assert turn.action == "turn"
    assert math.radians(145.1) / turn.duration == pytest.approx(HURRIED_TURN_RATE, rel=0.01)
    # Holding the cup it may not go over 65 deg/s (HURRIED_LOADED_TURN_RATE), which
    # leaves the parcel out of reach at its lift-off.
    with pytest.raises(PlanError) as info:
        compile_plan(scenario_from_text(TURNING_PICK_WITH_A_CUP))
    assert info.value.message.startswith("infeasible (reach): at the lift-off of 'parcel'")


def test_plan_prints_what_the_planner_changed(tmp_path: Path) -> None:
    path = _write(tmp_path, EARLY_TURNING_PICK % "1.94")
    result = runner.invoke(app, ["plan", str(path)])
    assert result.exit_code == 0, result.output
    assert "planner: the turn by 145 deg from 0.00 s ends at " in result.output
    assert "so that the trunk faces 'parcel' at its lift-off" in " ".join(result.output.split())


def _run_placing_the_parcel(tmp_path: Path, path: Path) -> tuple[str, dict[str, Any]]:
    """`locoplan run` on the script at `path`: it exits 0 with the robot standing, no joint
    past its torque limit and 'parcel' released onto 'platform' (MuJoCo's state, as the run's
    metrics report it). The run's output and metrics, for what a test asserts beyond that."""
    metrics_path = tmp_path / "metrics.json"
    result = runner.invoke(
        app,
        ["run", str(path), "--out", str(tmp_path / "runs"), "--metrics-json", str(metrics_path)],
    )
    assert result.exit_code == 0, result.output
    metrics = json.loads(metrics_path.read_text())
    assert not metrics["fell"] and metrics["peak_torque_ratio"] <= 1.0
    assert metrics["objects"]["parcel"]["on"] == "platform"
    assert not metrics["objects"]["parcel"]["held"]
    return result.output, metrics


@pytest.mark.closed_loop
def test_a_hurried_turn_picks_and_places_in_mujoco(tmp_path: Path) -> None:
    """Closed loop: the script that the planner used to refuse runs, says what the planner
    changed, and the parcel ends on the platform with the robot standing (MuJoCo's state,
    as the run's metrics report it)."""
    path = _write(
        tmp_path,
        EARLY_TURNING_PICK % "1.94"
        + "expect: {no_fall: true, max_torque_ratio: 1.0, placed: {parcel: platform}}\n",
    )
    output, metrics = _run_placing_the_parcel(tmp_path, path)
    assert "planner: the turn by 145 deg from 0.00 s ends at " in output
    assert len(metrics["planner_notes"]) == 1


# A transfer whose drop (start %s s) releases the parcel long before its 171 deg turn ends
# (envelope seed 48021, transfer-010: refused before `_face_the_drop`).
TURNING_DROP = """version: 1
name: turning-drop
gait: {period: 0.37, swing: 0.18}
objects:
  parcel: {shape: box, size: [0.142, 0.218, 0.224], mass: 0.52,
           position: [0.085, 0.313, 0.618], yaw: 74.8}
fixtures:
  table: {kind: table, position: [0.117, 0.431, 0.0], size: [0.328, 0.384, 0.506], yaw: 74.8}
  platform: {kind: platform, position: [-0.037, -0.326, 0.0], size: [0.312, 0.424, 0.489],
             yaw: -96.5}
tasks:
  - {action: turn, angle: 74.8, start: 0.0, duration: 1.64}
  - {action: pick, object: parcel, start: 0.82, duration: 1.05}
  - {action: turn, angle: -171.3, start: 1.87, duration: 4.65}
  - {action: drop, object: parcel, onto: platform, start: %s, duration: 1.19}
end: 7.52
"""


def _lowering_start(plan: Plan, task_index: int) -> float:
    return min(
        g.t0
        for track in plan.manipulation.tracks
        for g in track.segments
        if g.task_index == task_index and g.label == "lower"
    )


def test_a_drop_early_in_a_long_turn_hurries_the_turn_to_face_the_target() -> None:
    """A drop in the second half of the turn (inside issue 12's envelope) whose release
    comes before the trunk faces the platform: the planner ends the turn sooner, no quicker
    than a loaded turn may go, instead of refusing the script, and says so."""
    scenario = scenario_from_text(TURNING_DROP % "4.28")
    plan = compile_plan(scenario)
    turn = plan.tasks[2]
    assert turn.action == "turn" and turn.start == 1.87
    # Sooner than written (6.52 s), no quicker than HURRIED_LOADED_TURN_RATE.
    assert math.radians(171.3) / HURRIED_LOADED_TURN_RATE - 0.01 <= turn.duration
    assert turn.end < 6.52
    # It ends about when the hands start lowering the parcel onto the platform (the plan
    # that the written turn gave: the drop's phases are re-timed for the hurried one), well
    # before the release.
    assert abs(turn.end - _lowering_start(plan, 3)) < 0.1
    assert turn.end < plan.holds[0].release
    assert plan.notes == (
        f"the turn by 171 deg from 1.87 s ends at {turn.end:.2f} s instead of 6.52 s so that "
        "the trunk faces 'platform' at the release",
    )
    # The other tasks keep their written times.
    assert [(t.start, t.end) for i, t in enumerate(plan.tasks) if i != 2] == [
        (t.start, t.start + t.duration) for i, t in enumerate(scenario.tasks) if i != 2
    ]


def test_a_drop_too_early_for_the_quickest_turn_is_still_refused() -> None:
    # Released at 3.45 s: even at 65 deg/s the turn faces the platform only at 4.51 s.
    with pytest.raises(PlanError) as info:
        compile_plan(scenario_from_text(TURNING_DROP % "2.50"))
    exc = info.value
    assert exc.loc == ("tasks", 3) and exc.task_index == 3
    assert exc.message.startswith("infeasible (reach): at the release of 'parcel' onto ")
    assert "put the target nearer the robot or walk up to it before the drop" in exc.message


@pytest.mark.closed_loop
def test_a_hurried_turn_places_on_the_target_in_mujoco(tmp_path: Path) -> None:
    """Closed loop: the script that the planner used to refuse runs, and the parcel ends on
    the platform with the robot standing (MuJoCo's state, as the run's metrics report it)."""
    path = _write(tmp_path, TURNING_DROP % "4.28", "drop.yaml")
    _, metrics = _run_placing_the_parcel(tmp_path, path)
    assert metrics["planner_notes"][0].endswith("so that the trunk faces 'platform' at the release")


def test_validate_plan_run_and_compare_refuse_with_file_line_column(tmp_path: Path) -> None:
    path = _write(tmp_path, hold_script(30.0))
    for args in (
        ["validate", str(path)],
        ["plan", str(path)],
        # Refused while planning, before the scene is built: nothing is simulated.
        ["run", str(path), "--out", str(tmp_path / "runs"), "--quiet"],
        ["compare", str(path), "--out", str(tmp_path / "compare"), "--quiet", "--no-plots"],
    ):
        result = runner.invoke(app, args)
        assert result.exit_code == 2, (args, result.output)
        assert f"{path}:{PICK_AT}: infeasible (payload): 30 kg exceeds the " in result.output
        assert "carry at most" in result.output
    assert not (tmp_path / "runs").exists()  # no log opened


def test_batch_worker_refuses_before_simulating(tmp_path: Path) -> None:
    path = _write(tmp_path, hold_script(30.0))
    job = Job(str(path), "hold", str(path), path.read_text(), RunOptions(out_dir=tmp_path))
    outcome = execute_job(job)
    assert outcome.status == "error"
    # benchmarks/envelope.py counts "cannot plan: ... infeasible (<reason>):" as refused.
    assert outcome.message.startswith(f"cannot plan: {path}:{PICK_AT}: infeasible (payload)")
    assert not list(tmp_path.glob("*.mcap"))


def test_stdin_is_located_too() -> None:
    result = runner.invoke(app, ["validate", "-"], input=hold_script(30.0))
    assert result.exit_code == 2
    assert f"<stdin>:{PICK_AT}: infeasible (payload)" in result.output


def _strong_short_footed_robot(tmp_path: Path) -> Path:
    """HECTOR with 100 times its torque limits and 4 cm feet: balance, not torque, bounds
    what it holds."""
    folder = tmp_path / "robot"
    shutil.copytree(ROBOTS / "hector", folder)
    yaml_path = folder / "robot.yaml"
    text = yaml_path.read_text()
    text = text.replace("torque_Nm: 33.5", "torque_Nm: 3350").replace(
        "torque_Nm: 67.0", "torque_Nm: 6700"
    )
    text = text.replace("toe: 0.09", "toe: 0.02").replace("heel: 0.06", "heel: 0.02")
    yaml_path.write_text(text)
    xml = folder / "hector.xml"
    xml.write_text(
        xml.read_text()
        .replace('ctrlrange="-33.5 33.5"', 'ctrlrange="-3350 3350"')
        .replace('ctrlrange="-67 67"', 'ctrlrange="-6700 6700"')
    )
    return yaml_path


def test_balance_refusal_with_a_robot_whose_legs_bound_the_load(tmp_path: Path) -> None:
    robot = _strong_short_footed_robot(tmp_path)
    light = hold_script(1.0, str(robot), step_time=False)
    plan = compile_plan(load_scenario(_write(tmp_path, light, "a.yaml")))
    model = static_model(str(robot))
    limit = min(model.payload_limit(h.pose) for h in planned_holds(plan) if h.kind == "carry")
    assert 20.0 < limit < 200.0
    path = _write(tmp_path, hold_script(round(1.3 * limit), str(robot)), "heavy.yaml")
    result = runner.invoke(app, ["validate", str(path)])
    assert result.exit_code == 2, result.output
    # One line more than PICK_AT: the script's `robot:` line.
    assert f"{path}:10:5: infeasible (balance): in the carry pose of 'block'" in result.output
    assert "m ahead of the toes even with the pelvis" in result.output
    assert "the most the legs allow" in result.output
    # The heavier load is carried a little higher over its table (`carry_clearance` grows
    # with the mass: 0.4 cm/kg beyond 5 kg), so the limit the message states, that of the
    # heavy script's carry pose, is within 2 % of the light one's.
    stated = re.search(r"carry at most ([0-9.]+) kg", result.output)
    assert stated is not None, result.output
    assert float(stated.group(1)) == pytest.approx(limit, rel=0.02)


def test_plan_prints_the_margins_and_writes_them_to_json(tmp_path: Path) -> None:
    path = _write(tmp_path, hold_script(7.0))
    js = tmp_path / "plan.json"
    result = runner.invoke(app, ["plan", str(path), "--json", str(js)])
    assert result.exit_code == 0, result.output
    out = " ".join(result.output.split())
    assert "static payload margins" in out
    for text in (
        "block grasp (task 1)",
        "block carry (task 1)",
        "block place (task 3)",
        "torque ratio 0.4",
        "hip_pitch",
    ):
        assert text in out
    assert "reach margin" in out and "CoM margin" in out and "payload limit" in out
    rows = json.loads(js.read_text())["payload"]
    assert [(r["pose"], r["task"]) for r in rows] == [("grasp", 1), ("carry", 1), ("place", 3)]
    assert all(r["torque_ratio"] < 1.0 and r["payload_limit"] > 7.0 for r in rows[1:])
    assert rows[0]["mass"] == 0.0 and rows[0]["reach_margin"] > 0.0
    # The grasp's lift: inside the toes, with the lean the arms leave; none for the others.
    assert rows[0]["lift_margin"] >= 0.0 and rows[0]["lift_lean"] >= 0.03
    assert all(r["lift_margin"] is None for r in rows[1:])
    assert "lifting 7 kg" in out and "combined CoM" in out and "inside the toes" in out


NARROW_BOX_TO_A_HIGH_PLATFORM = Path(__file__).parent / "data" / "narrow-box-high-platform.yaml"


def test_plan_says_how_far_short_the_hands_stop_of_a_pose_out_of_reach(tmp_path: Path) -> None:
    """A box 0.114 m wide carried high enough to clear a 0.54 m platform (HECTOR envelope
    seed 54021, transfer-054): the hands, 9.4 cm apart at the carry height, are 2.5 cm short
    of it (shoulder roll; 4.5 cm gripped above the box's centre, `centre_grips`), and
    `locoplan plan` says so next to the reach margin; a pose in reach (the grasp) says
    nothing of the kind."""
    path = _write(tmp_path, NARROW_BOX_TO_A_HIGH_PLATFORM.read_text())
    js = tmp_path / "plan.json"
    result = runner.invoke(app, ["plan", str(path), "--json", str(js)])
    assert result.exit_code == 0, result.output
    out = " ".join(result.output.split())
    rows = {r["pose"]: r for r in json.loads(js.read_text())["payload"]}
    carry = rows["carry"]["reach_margin"]
    assert -0.035 < carry < -0.015
    assert f"hands stop up to {-carry:.3f} m short of this pose" in out
    assert rows["grasp"]["reach_margin"] > 0.0
    assert out.count("short of this pose") == sum(r["reach_margin"] < 0 for r in rows.values())


def _carry_clearance_left(plan: Plan, path: Path) -> float:
    """How far (m) the carried box of the one hold of `plan` (its scenario at `path`) passes
    over the highest fixture it sweeps over, held where the hands stop (the carry pose's
    height less its reach shortfall, `StaticPostures.arms`)."""
    scenario = load_scenario(path)
    (hold,) = plan.holds
    model = static_model(scenario.robot)
    (carry,) = [p for p in planned_holds(plan, model) if p.kind == "carry"]
    _, _, reach = model.postures.arms(carry.pose)
    z = sum(p[2] for p in carry.pose.p_hands_trunk) / 2
    half_z = scenario.objects[hold.object].size[2] / 2
    return plan.trunk.height + z - hold.grip_height - half_z + min(reach, 0.0) - hold.carry_top


def test_a_narrow_box_carried_over_a_high_target_is_gripped_at_its_centre(
    tmp_path: Path,
) -> None:
    """`payload.centre_grips`: the narrow box that must clear a 0.54 m platform is gripped at
    its centre, so that held where the arms stop it still passes over the platform (by more
    than the 1 cm it lacked gripped 4 cm above its centre); the same box carried to a
    0.40 m platform, in reach, keeps its grip above the centre (a pendulum that hangs
    level)."""
    plan = compile_plan(load_scenario(NARROW_BOX_TO_A_HIGH_PLATFORM))
    (hold,) = plan.holds
    assert hold.grip_height == 0.0 and hold.carry_top == pytest.approx(0.54)
    assert _carry_clearance_left(plan, NARROW_BOX_TO_A_HIGH_PLATFORM) > 0.01
    low = _write(
        tmp_path,
        NARROW_BOX_TO_A_HIGH_PLATFORM.read_text().replace("0.444, 0.54]", "0.444, 0.40]"),
    )
    (kept,) = compile_plan(load_scenario(low)).holds
    assert kept.grip_height > 0.0


@pytest.mark.closed_loop
def test_a_narrow_box_carried_over_a_high_target_is_placed_in_mujoco(tmp_path: Path) -> None:
    """Closed loop (dynamic: the drop starts in the turn towards the platform): the box
    reaches the platform and stays on it (gripped above its centre it came down on the
    platform's edge 0.4 s before the drop and was left there)."""
    path = _write(
        tmp_path,
        NARROW_BOX_TO_A_HIGH_PLATFORM.read_text()
        + "expect: {no_fall: true, max_torque_ratio: 1.0, placed: {parcel: platform}}\n",
    )
    _run_placing_the_parcel(tmp_path, path)


def test_plan_without_holds_prints_no_margins(tmp_path: Path) -> None:
    result = runner.invoke(app, ["plan", str(scenario_files()[0].parent / "turn.yaml")])
    assert result.exit_code == 0
    assert "static payload margins" not in result.output


def test_repository_scripts_are_not_refused() -> None:
    for path in scenario_files():
        scenario = load_scenario(path)
        for strategy in ("dynamic", "quasi-static"):
            plan = compile_robot_plan(scenario, strategy)  # raises if refused
            for m in payload_margins(plan, scenario.robot):
                assert m.analysis.torque_ratio < 1.0, (path, m.hold)


def test_envelope_scripts_are_not_refused(tmp_path: Path) -> None:
    # Refusing inside the envelope counts against the planner. A 150-script suite (the
    # generator's mix, seed 4242), written out and loaded as `locoplan validate` loads them,
    # every family but the generated transfers, whose compile alone (the hand paths) takes
    # 1-78 s each on a loaded 2-core machine; issue 12's two transfer examples stand in for
    # them. The transfers carry at most 6 kg: over the 90 of seed 2026's 300 scripts, all
    # checked once by hand in both strategies, the worst pose was at ratio 0.40 (the worst
    # of all 300: a 12.95 kg hold put back on its table, 0.84).
    # Six standing holds of 11.5-13.9 kg gripped 0.32-0.39 m out on this seed are lifts the
    # robot cannot balance from where it stands (`check_lift`); their picks start with a step
    # nearer instead (tests/test_step_in.py), as do four whose lift balances with less than
    # the grasp tolerance to spare.
    scripts = [s for s in generate_suite(150, 4242) if s.family != "transfer"]
    assert {s.family for s in scripts} == set(FAMILIES) - {"transfer"}
    paths = sorted(ENVELOPE_EXAMPLES.glob("transfer-*.yaml"))
    assert len(paths) == 2
    for script in scripts:
        path = tmp_path / script.family / f"{script.name}.yaml"
        path.parent.mkdir(exist_ok=True)
        path.write_text(script.text)
        paths.append(path)
    stepped = []
    for path in paths:
        scenario = load_scenario_file(path).scenario
        plan = compile_plan(scenario)  # raises if refused
        check_payload(plan, scenario.robot)
        for note in plan.notes:
            if "starts with a step" in note:
                stepped.append((path.stem, "tolerance" in note.rsplit(": ", 1)[1]))
    past = [
        "standing-hold-000",
        "standing-hold-002",
        "standing-hold-003",
        "standing-hold-007",
        "standing-hold-010",
        "standing-hold-012",
    ]
    on_the_tolerance = [
        "standing-hold-005",
        "standing-hold-009",
        "standing-hold-013",
        "standing-hold-018",
    ]
    assert sorted(stepped) == sorted(
        [(name, False) for name in past] + [(name, True) for name in on_the_tolerance]
    )


def test_lift_margin_limits_are_where_the_combined_centre_of_mass_meets_the_bound() -> None:
    # Robot 17 kg with its CoM over the sole sites, toes 0.09 m ahead, load at 0.30 m:
    # (17 x 0 + m x 0.30) / (17 + m) = 0.10 at m = 8.5 kg; 10 kg balances at 0.27 m.
    m = LiftMargin(margin=-0.05, robot_x=0.0, load_x=0.30, toe=0.09, robot_mass=17.0)
    assert m.mass_limit(0.01) == pytest.approx(8.5)
    assert m.nearer(10.0, 0.01) == pytest.approx(0.03)
    assert LiftMargin(0.2, 0.0, 0.05, 0.09, 17.0).mass_limit(0.01) == math.inf
    assert LiftMargin(0.01, 0.0, 0.05, 0.09, 17.0).nearer(1.0, 0.01) == 0.0


PACKAGE_TRANSFER = Path(__file__).resolve().parents[1] / "scenarios" / "package-transfer.yaml"


def _conveyor_at(x: float) -> str:
    """scenarios/package-transfer.yaml with its conveyor's centre moved to (x, 0)."""
    text = PACKAGE_TRANSFER.read_text()
    assert "position: [0.35, 0.0, 0.0]" in text
    return text.replace("position: [0.35, 0.0, 0.0]", f"position: [{x!r}, 0.0, 0.0]", 1)


def test_drop_target_out_of_reach_is_refused_at_the_drop() -> None:
    """A conveyor 1 m away: the hands would release the package 0.5 m short of it."""
    with pytest.raises(PlanError) as info:
        compile_plan(scenario_from_text(_conveyor_at(1.0)))
    exc = info.value
    assert exc.loc == ("tasks", 3) and exc.task_index == 3
    assert exc.message.startswith("infeasible (reach): at the release of 'package' onto 'conveyor'")
    assert "put the target nearer the robot" in exc.message
    compile_plan(scenario_from_text(_conveyor_at(0.35)))  # the repository's own: placed


@pytest.mark.parametrize(("x", "refused"), [(0.53, False), (0.55, False), (0.57, True)])
def test_a_drop_whose_object_would_end_at_the_edge_is_refused(x: float, refused: bool) -> None:
    """The conveyor 0.53 / 0.55 / 0.57 m ahead: the hands miss the place points by 5.6 / 7.4 /
    9.3 cm and the package's planned centre lies 12 cm inside the belt's near edge. Closed
    loop, the first two are placed and the third is released at the edge and not placed
    (PLACE_SLACK's docstring): the allowed miss leaves the centre PLACE_SLACK inside."""
    scenario = scenario_from_text(_conveyor_at(x))
    if not refused:
        compile_plan(scenario)
        return
    with pytest.raises(PlanError) as info:
        compile_plan(scenario)
    msg = info.value.message
    assert msg.startswith("infeasible (reach): at the release of 'package' onto 'conveyor'")
    assert f"must stay {PLACE_SLACK:.2f} m inside it" in msg
    assert "0.12 m inside the edge" in msg and "allowed 0.09 m" in msg


@pytest.mark.parametrize(
    ("x", "message"),
    [
        (900.0, "infeasible (reach): at the release of 'package'"),
        (1.0e9, "position values must be <= 1000 m, got 1000000000.0"),
    ],
)
def test_a_fixture_far_away_is_refused_not_planned_forever(
    tmp_path: Path, x: float, message: str
) -> None:
    """Found by the fuzz test: a fixture 1e9 m away made the drop's retreat last 9.5e9 s and
    its clearance check sample it every 10 ms; `validate` never returned. The format now
    bounds a scene's lengths to 1000 m (`scenario.model.MAX_LENGTH`), so 1e9 m is refused as
    a typo; 900 m, inside that bound, is refused by the plan's reach check in seconds. A
    subprocess, so that a hang fails on the timeout instead of holding the suite."""
    import subprocess
    import sys

    path = _write(tmp_path, _conveyor_at(x), "far.yaml")
    res = subprocess.run(
        [sys.executable, "-m", "locoplan", "validate", str(path)],
        capture_output=True, text=True, timeout=120, check=False,
    )  # fmt: skip
    assert res.returncode == 2, res.stdout + res.stderr
    assert message in res.stdout


def test_clearance_check_samples_a_long_segment_at_most_max_times(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from locoplan.plan import clearance_kernels
    from locoplan.plan import constants as k
    from locoplan.plan.clearance import Obstacle, track_clearance

    plan = compile_plan(load_scenario(PACKAGE_TRANSFER))
    calls: list[float] = []
    gaps = clearance_kernels.sample_gaps

    def counting(points: Any, ts: Any, *args: Any) -> Any:
        calls.extend(ts.tolist())
        return gaps(points, ts, *args)

    monkeypatch.setattr(clearance_kernels, "sample_gaps", counting)
    wall = Obstacle("wall", (5.0, 0.0, 0.5), (0.1, 0.1, 0.5), 0.0)
    track = plan.manipulation.tracks[0]
    c = track_clearance(track, plan.trunk, (wall,), 0.0, 1.0e7, 0.025, yaw_offsets=(0.0,))
    assert len(calls) == k.MAX_CLEARANCE_SAMPLES + 1
    # The latest sample first; the hand stays within a metre of the start, the wall's face
    # 4.9 m ahead.
    assert calls[0] == 1.0e7 and 3.0 < c.minimum < 4.9
