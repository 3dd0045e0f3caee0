"""Feasibility refusals before simulating (locoplan.scenario.feasibility): every reason is
triggered from a task script, reported at file:line:column with exit 2, and says what would make
the script feasible; scripts inside the envelope are not refused."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from locoplan.envelope import generate_suite
from locoplan.exceptions import ScenarioError
from locoplan.scenario.feasibility import check_feasibility
from locoplan.scenario.loader import load_scenario, load_scenario_file

HEAD = """version: 1
name: feas
gait: {period: 0.4, swing: 0.15}
"""


def _issues(text: str, tmp_path: Path) -> list[str]:
    path = tmp_path / "s.yaml"
    path.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario_file(path)
    return [f"{i.line}:{i.column}: {i.message}" for i in info.value.issues]


def test_walk_faster_than_the_legs_step_is_refused_with_the_duration_it_needs(
    tmp_path: Path,
) -> None:
    text = HEAD + "tasks:\n  - {action: walk, distance: [100, 0], start: 0, duration: 2}\n"
    [msg] = _issues(text, tmp_path)
    assert msg.startswith("5:")
    # The cruise profile peaks at 1.5x the 50 m/s average.
    assert "infeasible (rate): walk of 100 m in 2 s peaks at 75 m/s" in msg
    # 0.18 m half stride per 0.4 s period: 0.45 m/s at the peak, so 100 m needs 1.5 x 222 s
    # (rounded up to 0.01 s)
    assert "at most 0.45 m/s" in msg
    assert "at least 333.34 s" in msg


def test_turn_quicker_than_the_hip_yaw_range_allows_is_refused(tmp_path: Path) -> None:
    text = HEAD + "tasks:\n  - {action: turn, angle: 180, start: 0, duration: 0.5}\n"
    [msg] = _issues(text, tmp_path)
    assert "infeasible (rate): turn by 180 deg in 0.5 s peaks at 540 deg/s" in msg
    # 2 x 30 deg per 0.4 s period = 150 deg/s at the peak: 1.5 x 180 / 150 = 1.8 s
    assert "at most 150 deg/s" in msg
    assert "at least 1.80 s" in msg


def _standing_by(box: str, fixtures: str = "", head: str = HEAD) -> str:
    """A script that stands 1 s beside the object `box` (a flow mapping) and `fixtures`."""
    return (
        head
        + f"objects:\n  box: {box}\n"
        + fixtures
        + "tasks:\n  - {action: stand, start: 0, duration: 1}\n"
    )


def test_object_inside_the_robot_is_refused(tmp_path: Path) -> None:
    text = _standing_by("{shape: box, size: [0.1, 0.1, 0.1], mass: 1, position: [0.05, 0, 0.5]}")
    [msg] = _issues(text, tmp_path)
    assert msg.startswith("5:")
    assert "infeasible (overlap): object 'box' comes within 0.000 m" in msg
    assert "inside its body" in msg and "move it at least 0.136 m further away" in msg


def test_object_sunk_into_its_table_is_refused_with_the_resting_height(tmp_path: Path) -> None:
    text = _standing_by(
        "{shape: box, size: [0.2, 0.2, 0.2], mass: 1, position: [0.4, 0, 0.45]}",
        "fixtures:\n  table: {kind: table, position: [0.5, 0, 0], size: [0.4, 0.6, 0.45]}\n",
    )
    [msg] = _issues(text, tmp_path)
    assert "infeasible (overlap): object 'box' sits 0.100 m inside fixture 'table'" in msg
    assert "centre at z = 0.550 m" in msg


def test_h1_is_checked_against_its_own_legs_and_feet(tmp_path: Path) -> None:
    """The limits come from the script's robot (robot.yaml `planner`, `foot`, `stance_width`):
    H1's hip yaw range is +-24.6 deg (HECTOR's 30), its stride 0.31 m (0.18), and its feet
    cover 0.246 m around the start (hypot(toe 0.14, half stance 0.203); HECTOR's 0.135)."""
    head = HEAD + "robot: h1\n"
    turn = head + "tasks:\n  - {action: turn, angle: 180, start: 0, duration: 1.5}\n"
    [msg] = _issues(turn, tmp_path)
    # 2 x 24.6 deg per 0.4 s = 123 deg/s at the peak; 1.5 x 180 / 123 = 2.19 s.
    assert "the hip yaw range (+-24.6 deg) allows at most 123 deg/s" in msg
    assert "at least 2.20 s" in msg
    walk = head + "tasks:\n  - {action: walk, distance: [1.5, 0], start: 0, duration: 2.5}\n"
    [msg] = _issues(walk, tmp_path)
    # 0.31 m per 0.4 s period: 0.775 m/s (HECTOR would refuse it already at 0.45 m/s).
    assert "at most 0.775 m/s" in msg and "peaks at 0.9 m/s" in msg
    near = _standing_by(
        "{shape: box, size: [0.1, 0.1, 0.1], mass: 1, position: [0.25, 0, 0.5]}", head=head
    )
    [msg] = _issues(near, tmp_path)
    assert "comes within 0.200 m of the robot's start position" in msg
    assert "the robot needs 0.246 m" in msg
    # HECTOR stands beside the same box.
    (tmp_path / "hector.yaml").write_text(near.replace("robot: h1\n", ""))
    load_scenario_file(tmp_path / "hector.yaml")


def test_validate_exits_2_with_file_line_column(tmp_path: Path) -> None:
    path = tmp_path / "fast.yaml"
    path.write_text(
        HEAD + "tasks:\n  - {action: walk, distance: [100, 0], start: 0, duration: 2}\n"
    )
    out = subprocess.run(
        [sys.executable, "-m", "locoplan", "validate", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert out.returncode == 2
    assert f"{path}:5:" in out.stdout + out.stderr
    assert "Traceback" not in out.stdout + out.stderr


@pytest.mark.parametrize("seed", [11, 12])
def test_envelope_scripts_are_not_refused(seed: int) -> None:
    # Refusing inside the envelope counts against the planner: none of these may be refused.
    for script in generate_suite(60, seed):
        scenario = load_scenario(script.name, script.text)
        assert check_feasibility(scenario) == [], script.text


def test_repository_scripts_are_not_refused() -> None:
    root = Path(__file__).resolve().parents[1] / "scenarios"
    for path in sorted(root.glob("*.yaml")):
        assert check_feasibility(load_scenario(path)) == [], path
