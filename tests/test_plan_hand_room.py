"""Room for the hands beside an object before the grasp (`hand_paths.pregrasp_offset`, the
`infeasible (hand room)` refusal of `ManipulationPlan.pick`, the entry paths of
`hand_paths.approach_segments`) and the envelope generator's side-carry layouts that keep it.

The scripts are side-carries drawn by the envelope generator before it kept that room (their
platform stands beside the box): HECTOR's seed 66021 side-carry-005 (4.2 cm between box and
platform, the hand 4 cm across: fell in both strategies) and H1's seed 16021 side-carry-016
(10.9 cm, the hand 6.6 cm across: the left hand's reach cut 3.6 cm into the platform's edge
and the robot fell backwards at 1.5 s; it places the box now)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from plan_fixtures import scenario_from_text
from typer.testing import CliRunner

from locoplan.cli import app
from locoplan.envelope import generate_suite
from locoplan.envelope.compose import rect_of
from locoplan.envelope.geometry import rects_apart
from locoplan.envelope.ranges import HECTOR_RANGES, envelope_ranges
from locoplan.plan import constants as k
from locoplan.plan.clearance import Obstacle, fixture_obstacle, track_clearance
from locoplan.plan.errors import InfeasiblePlanError
from locoplan.plan.hand_paths import pregrasp_offset
from locoplan.plan.robot_geometry import HECTOR_GEOMETRY
from locoplan.scenario import load_scenario_file
from locoplan.sim.robot_plan import compile_robot_plan
from locoplan.sim.run import RunOptions, run_scenario

runner = CliRunner()

HECTOR_CROWDED = """version: 1
name: side-carry-005
gait: {period: 0.45, swing: 0.15}
objects:
  box: {shape: box, size: [0.164, 0.225, 0.166], mass: 1.82, position: [0.348, 0.0, 0.491]}
fixtures:
  table: {kind: table, position: [0.558, 0.0, 0.0], size: [0.513, 0.259, 0.408], yaw: 0.0}
  platform: {kind: platform, position: [0.476, PLATFORM_Y, 0.0], size: [0.555, 0.31, 0.532]}
tasks:
  - {action: pick, object: box, start: 0.5, duration: 0.86}
  - {action: walk, distance: [0.0, -0.309], start: 1.47, duration: 2.38}
  - {action: drop, object: box, onto: platform, start: 3.89, duration: 1.05}
end: 5.94
expect: {no_fall: true, max_torque_ratio: 1.0, placed: {box: platform}}
"""
PICK_LINE = 10  # line of the pick task in HECTOR_CROWDED

H1_BESIDE = """version: 1
name: side-carry-016
robot: h1
gait: {period: 0.35, swing: 0.16}
objects:
  box: {shape: box, size: [0.244, 0.161, 0.156], mass: 2.92, position: [0.438, 0.0, 1.032]}
fixtures:
  table: {kind: table, position: [0.608, 0.0, 0.0], size: [0.522, 0.305, 0.954], yaw: 0.0}
  platform: {kind: platform, position: [0.447, 0.411, 0.0], size: [0.352, 0.443, 1.066], yaw: 0.0}
tasks:
  - {action: pick, object: box, start: 0.5, duration: 0.85}
  - {action: walk, distance: [0.0, 0.411], start: 1.45, duration: 1.71}
  - {action: drop, object: box, onto: platform, start: 3.39, duration: 1.49}
end: 5.88
expect: {no_fall: true, max_torque_ratio: 1.0, placed: {box: platform}}
"""


def _wall(near_y: float, top: float) -> Obstacle:
    """A platform whose near edge runs along x at y = near_y (m), from the floor to `top`."""
    return Obstacle("fixture:platform", (0.4, near_y + 0.2, top / 2.0), (0.3, 0.2, top / 2.0))


def test_a_free_side_keeps_the_nominal_pre_grasp_point() -> None:
    geo = HECTOR_GEOMETRY
    room = pregrasp_offset((0.35, 0.0, 0.5), (0.0, 1.0), 0.1, (), 0.0, geo)
    assert room.offset == geo.grasp_clearance and room.clearance == math.inf
    # A platform 10 cm beside the side, taller than the grip: the sphere is 3 cm off the side
    # at the nominal point and 10 - 5 - 2 = 3 cm off the platform: nothing to move.
    room = pregrasp_offset((0.35, 0.0, 0.5), (0.0, 1.0), 0.1, (_wall(0.2, 0.6),), 0.0, geo)
    assert room.offset == geo.grasp_clearance
    assert room.clearance == pytest.approx(0.1 - geo.grasp_clearance - geo.hand_radius, abs=1e-12)


@pytest.mark.parametrize("gap", [0.05, 0.07, 0.09])
def test_a_platform_beside_the_box_puts_the_hand_between_them(gap: float) -> None:
    # The side at y = 0.1, the platform's near edge `gap` further: the hand point waits in the
    # middle (on the PREGRASP_STEP grid), its sphere as far from both.
    geo = HECTOR_GEOMETRY
    r = geo.hand_radius
    room = pregrasp_offset((0.35, 0.0, 0.5), (0.0, 1.0), 0.1, (_wall(0.1 + gap, 0.6),), 0.0, geo)
    assert room.obstacle == "fixture:platform"
    assert room.offset == pytest.approx(gap / 2.0, abs=k.PREGRASP_STEP / 2.0 + 1e-12)
    assert room.clearance == pytest.approx(gap / 2.0 - r, abs=k.PREGRASP_STEP / 2.0 + 1e-12)
    # A platform lower than the hand sphere's bottom is no obstacle to it.
    low = pregrasp_offset((0.35, 0.0, 0.5), (0.0, 1.0), 0.1, (_wall(0.1 + gap, 0.4),), 0.0, geo)
    assert low.offset == geo.grasp_clearance


def test_no_room_for_the_hand_is_refused_with_how_far_to_move_the_fixture() -> None:
    text = HECTOR_CROWDED.replace("PLATFORM_Y", "-0.309")
    with pytest.raises(InfeasiblePlanError) as info:
        compile_robot_plan(scenario_from_text(text))
    exc = info.value
    assert exc.loc == ("tasks", 0) and exc.task_index == 0
    m = re.fullmatch(
        r"infeasible \(hand room\): no room for the R hand beside 'box' before the grasp: "
        r"wherever it waits between the side of 'box' and 'platform', its sphere \(0\.040 m "
        r"across\) keeps at most (-?[0-9.]+|\+[0-9.]+) m from 'platform' \(0\.005 m needed\); "
        r"move 'platform' ([0-9.]+) m further from 'box'",
        exc.message,
    )
    assert m is not None, exc.message
    # 4.2 cm between the box's side and the platform's near edge for a hand 4 cm across.
    assert float(m.group(1)) < k.PREGRASP_GAP
    # Moved as far as the message says, the platform leaves the room: the pick is planned.
    further = float(m.group(2))
    moved = HECTOR_CROWDED.replace("PLATFORM_Y", f"{-0.309 - further:.3f}")
    compile_robot_plan(scenario_from_text(moved))


def test_validate_plan_and_run_refuse_a_crowded_pick_with_file_line_column(
    tmp_path: Path,
) -> None:
    path = tmp_path / "crowded.yaml"
    path.write_text(HECTOR_CROWDED.replace("PLATFORM_Y", "-0.309"))
    for args in (
        ["validate", str(path)],
        ["plan", str(path)],
        ["run", str(path), "--out", str(tmp_path / "runs")],
    ):
        result = runner.invoke(app, args)
        assert result.exit_code == 2, (args, result.output)
        assert f"{path}:{PICK_LINE}:5: infeasible (hand room): no room for the R hand" in (
            " ".join(result.output.split())
        )
    assert not (tmp_path / "runs").exists()  # refused before a log is opened


def test_h1_hand_waits_between_box_and_platform_and_reaches_around_its_edge() -> None:
    scenario = scenario_from_text(H1_BESIDE)
    plan = compile_robot_plan(scenario)
    geo = plan.geometry
    track = plan.manipulation.tracks[0]  # the left hand, on the platform's side
    (squeeze,) = [g for g in track.segments if g.label == "squeeze"]
    # The nominal point (6.3 cm off the side) left the sphere 1.3 cm from the platform, 3 cm
    # from the box; between them: about 2.1 cm from each (10.9 cm gap, 6.6 cm hand).
    offset = squeeze.start.point[1] - scenario.objects["box"].size[1] / 2.0
    assert offset < geo.grasp_clearance - 0.005
    platform = (fixture_obstacle("platform", scenario.fixtures["platform"]),)
    # The planner's own check (planned trunk, yaw off by its expected error): the approach,
    # tuck to squeeze, keeps out of the platform (-3.6 cm by the straight reach the
    # planner took when no path kept its 2.5 cm; now by way of the entry point).
    approach = [g for g in track.segments if g.t1 <= squeeze.t1]
    c = track_clearance(
        track, plan.trunk, platform, approach[0].t0, squeeze.t1, 0.0, hand_radius=geo.hand_radius
    )
    assert c.minimum >= 0.0, c
    assert any(g.label == "slide" for g in approach)


@pytest.mark.closed_loop
def test_h1_side_carry_beside_a_platform_places_the_box(tmp_path: Path) -> None:
    # About 8 s of wall time (5.9 s simulated). At the base revision the left hand hit the
    # platform's edge at 0.65 s, pushed the trunk back and H1 fell at 1.5 s.
    path = tmp_path / "side-carry-016.yaml"
    path.write_text(H1_BESIDE)
    loaded = load_scenario_file(path)
    result = run_scenario(loaded.scenario, loaded.text, RunOptions(out_dir=tmp_path))
    rec = result.record
    assert not result.metrics["fell"]
    # The pelvis never more than 3 cm below its nominal 0.98 m.
    assert np.min(np.asarray(rec.base_position)[:, 2]) > 0.95
    # The box ends on the platform: its centre above the platform's footprint, resting on
    # its top (half its height above, 1 cm for contact).
    box, platform = loaded.scenario.objects["box"], loaded.scenario.fixtures["platform"]
    end = np.asarray(rec.object_positions["box"])[-1]
    assert abs(end[2] - (platform.size[2] + box.size[2] / 2.0)) < 0.01
    assert abs(end[1] - platform.position[1]) < platform.size[1] / 2.0
    assert result.metrics["passed"]


@pytest.mark.parametrize("robot", [None, "h1"])
def test_generated_side_carries_keep_room_for_the_hands(robot: str | None) -> None:
    ranges = HECTOR_RANGES if robot is None else envelope_ranges(robot)
    for s in generate_suite(40, 66021, ["side-carry"], robot):
        doc = scenario_from_text(s.text)
        box, platform = doc.objects["box"], doc.fixtures["platform"]
        box_rect = rect_of({"position": box.position, "size": box.size, "yaw": box.yaw})
        goal = rect_of({"position": platform.position, "size": platform.size, "yaw": platform.yaw})
        assert rects_apart(box_rect, goal, ranges.hand_room), s.name
        compile_robot_plan(doc)  # and none is refused
