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
    """Every scenario file shipped in scenarios/."""
    return sorted(SCENARIO_DIR.glob("*.yaml"))
