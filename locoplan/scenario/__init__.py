"""Task scripts: pydantic models and YAML loading with line/column errors.

The only package that imports pydantic. Entry points: `load_scenario(path)` -> `Scenario`,
`load_scenario_file(path)` -> `LoadedScenario` (the scenario with its path and text), both
raising `locoplan.exceptions.ScenarioError`; `scenario_json_schema()`.
"""

from locoplan.scenario.loader import LoadedScenario, load_scenario, load_scenario_file
from locoplan.scenario.model import (
    ACTIONS,
    LOCOMOTION_ACTIONS,
    MANIPULATION_ACTIONS,
    DropTask,
    Expectations,
    FixtureSpec,
    GaitSettings,
    MpcSettings,
    ObjectSpec,
    PickTask,
    RobotStart,
    Scenario,
    StandTask,
    StepTask,
    Task,
    ThrowTask,
    TurnTask,
    WalkTask,
)
from locoplan.scenario.schema import scenario_json_schema
from locoplan.scenario.semantics import check_semantics

__all__ = [
    "ACTIONS",
    "LOCOMOTION_ACTIONS",
    "MANIPULATION_ACTIONS",
    "DropTask",
    "Expectations",
    "FixtureSpec",
    "GaitSettings",
    "LoadedScenario",
    "MpcSettings",
    "ObjectSpec",
    "PickTask",
    "RobotStart",
    "Scenario",
    "StandTask",
    "StepTask",
    "Task",
    "ThrowTask",
    "TurnTask",
    "WalkTask",
    "check_semantics",
    "load_scenario",
    "load_scenario_file",
    "scenario_json_schema",
]
