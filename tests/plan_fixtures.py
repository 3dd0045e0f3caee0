"""Shared helpers of the plan tests: scenarios from YAML text and the repository's files."""

from __future__ import annotations

from pathlib import Path

from locoplan.scenario import load_scenario
from locoplan.scenario.model import Scenario

SCENARIO_DIR = Path(__file__).resolve().parent.parent / "scenarios"


def scenario_from_text(text: str) -> Scenario:
    """A validated scenario from YAML text (through the real loader)."""
    return load_scenario("<test>", text)


def repo_scenario(name: str) -> Scenario:
    """A scenario of the repository's scenarios/ folder, by file stem."""
    return load_scenario(SCENARIO_DIR / f"{name}.yaml")


def scenario_files() -> list[Path]:
    """Every scenario file shipped in scenarios/ (HECTOR's and H1's)."""
    return sorted(SCENARIO_DIR.glob("*.yaml"))


def hector_scenario_files() -> list[Path]:
    """The scenario files of scenarios/ written for HECTOR (the default robot), for tests that
    check a plan against HECTOR's own figures."""
    return [p for p in scenario_files() if load_scenario(p).robot == "hector"]


def stand_script(robot: str, duration: float) -> str:
    """A script in which `robot` only stands for `duration` s."""
    return f"""version: 1
name: {robot}-stand
robot: {robot}
tasks:
  - {{action: stand, start: 0.0, duration: {duration}}}
"""


def hold_script(mass: float, robot: str | None = None, step_time: bool = True) -> str:
    """A standing hold from a table in front, put back (issue 12's hold-11kg geometry).
    `step_time` False: the put-back starts 0.7 s after the pick, which leaves no time for
    the step nearer that the planner takes before a heavy standing lift
    (`compiler._step_in_off_the_tolerance`), so the robot lifts from where the script
    stands it (for tests of the poses and margins of that stance)."""
    head = f"robot: {robot}\n" if robot else ""
    stand, drop = ("3.0", "5.5") if step_time else ("0.7", "3.2")
    return f"""version: 1
name: hold
{head}objects:
  block: {{shape: box, size: [0.211, 0.234, 0.169], mass: {mass}, position: [0.356, 0.0, 0.543]}}
fixtures:
  table: {{kind: table, position: [0.48, 0.0, 0.0], size: [0.4, 0.6, 0.459]}}
tasks:
  - {{action: stand, start: 0.0, duration: 0.5}}
  - {{action: pick, object: block, start: 0.5, duration: 2.0}}
  - {{action: stand, start: 2.5, duration: {stand}}}
  - {{action: drop, object: block, onto: table, start: {drop}, duration: 1.5}}
end: 8.0
"""
