"""Task scripts: pydantic models and YAML loading with line/column errors.

The only package that imports pydantic.
"""

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

__all__ = [
    "ACTIONS",
    "LOCOMOTION_ACTIONS",
    "MANIPULATION_ACTIONS",
    "DropTask",
    "Expectations",
    "FixtureSpec",
    "GaitSettings",
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
]
