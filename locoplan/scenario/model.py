"""Pydantic v2 models of the task-script format, version 1 (`shared/scenario-format.md`).

These models check types and per-field ranges only; cross-field rules (objects held,
overlapping locomotion, tasks past `end`) live in `locoplan.scenario.semantics` so that each
error can point at the exact YAML node. Angles stay in degrees here, as in the file; the plan
compiler converts to radians.
"""

from __future__ import annotations

from typing import Annotated, ClassVar, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

Vec2 = Annotated[list[float], Field(min_length=2, max_length=2)]
Vec3 = Annotated[list[float], Field(min_length=3, max_length=3)]

# Finite-ness is checked for every float: YAML accepts .inf and .nan.
FiniteFloat = Annotated[float, Field(allow_inf_nan=False)]
PositiveTime = Annotated[float, Field(gt=0.0, allow_inf_nan=False)]
NonNegTime = Annotated[float, Field(ge=0.0, allow_inf_nan=False)]

ACTIONS = ("stand", "step", "walk", "turn", "pick", "drop", "throw")
LOCOMOTION_ACTIONS = ("step", "walk", "turn")
MANIPULATION_ACTIONS = ("pick", "drop", "throw")


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class RobotStart(_Strict):
    position: Annotated[list[FiniteFloat], Field(min_length=2, max_length=2)] = [0.0, 0.0]
    yaw: FiniteFloat = 0.0


class MpcSettings(_Strict):
    dt: Annotated[float, Field(gt=0.0, le=0.2, allow_inf_nan=False)] = 0.03
    horizon: Annotated[int, Field(ge=2, le=100)] = 20


class GaitSettings(_Strict):
    """Stepping gait: `period` is one full cycle (left swing then right swing), `swing` the
    swing time of one foot. Double support per half cycle is period/2 - swing."""

    period: Annotated[float, Field(gt=0.0, le=5.0, allow_inf_nan=False)] = 0.4
    swing: Annotated[float, Field(gt=0.0, le=2.5, allow_inf_nan=False)] = 0.15

    @model_validator(mode="after")
    def _swing_fits(self) -> GaitSettings:
        if self.swing > self.period / 2 + 1e-12:
            raise ValueError(
                f"gait swing {self.swing} s is longer than half the period "
                f"({self.period / 2} s); allowed: 0 < swing <= period / 2"
            )
        return self


class ObjectSpec(_Strict):
    shape: Literal["box", "sphere"]
    size: Annotated[list[Annotated[float, Field(gt=0.0, allow_inf_nan=False)]], Field(min_length=1)]
    mass: Annotated[float, Field(gt=0.0, le=1000.0, allow_inf_nan=False)]
    position: Annotated[list[FiniteFloat], Field(min_length=3, max_length=3)]
    yaw: FiniteFloat = 0.0

    @model_validator(mode="after")
    def _size_matches_shape(self) -> ObjectSpec:
        want = 3 if self.shape == "box" else 1
        if len(self.size) != want:
            what = "[x, y, z] full extents" if self.shape == "box" else "[radius]"
            raise ValueError(
                f"a {self.shape} needs size {what} ({want} value{'s' if want > 1 else ''}), "
                f"got {len(self.size)}"
            )
        return self


class FixtureSpec(_Strict):
    kind: Literal["table", "conveyor", "platform"]
    position: Annotated[list[FiniteFloat], Field(min_length=3, max_length=3)]
    size: Annotated[
        list[Annotated[float, Field(gt=0.0, allow_inf_nan=False)]],
        Field(min_length=3, max_length=3),
    ]
    yaw: FiniteFloat = 0.0
    speed: FiniteFloat | None = None

    @model_validator(mode="after")
    def _speed_only_on_conveyor(self) -> FixtureSpec:
        if self.speed is not None and self.kind != "conveyor":
            raise ValueError(f"'speed' is allowed on a conveyor only, not on a {self.kind}")
        return self

    @property
    def top_height(self) -> float:
        return self.size[2]


class _TaskBase(_Strict):
    start: NonNegTime
    duration: PositiveTime

    @property
    def end(self) -> float:
        return self.start + self.duration


class StandTask(_TaskBase):
    action: Literal["stand"]


class StepTask(_TaskBase):
    action: Literal["step"]


class WalkTask(_TaskBase):
    action: Literal["walk"]
    distance: Annotated[list[FiniteFloat], Field(min_length=2, max_length=2)]


class TurnTask(_TaskBase):
    action: Literal["turn"]
    angle: FiniteFloat


class PickTask(_TaskBase):
    action: Literal["pick"]
    object: str
    hands: Literal["both", "left", "right"] = "both"


class DropTask(_TaskBase):
    action: Literal["drop"]
    object: str
    onto: str | None = None
    at: Annotated[list[FiniteFloat], Field(min_length=3, max_length=3)] | None = None

    @model_validator(mode="after")
    def _one_target(self) -> DropTask:
        if (self.onto is None) == (self.at is None):
            raise ValueError("a drop needs exactly one target: 'onto: FIXTURE' or 'at: [x, y, z]'")
        return self


class ThrowTask(_TaskBase):
    action: Literal["throw"]
    object: str
    velocity: Annotated[list[FiniteFloat], Field(min_length=3, max_length=3)]


Task = Annotated[
    StandTask | StepTask | WalkTask | TurnTask | PickTask | DropTask | ThrowTask,
    Field(discriminator="action"),
]
ManipulationTask = PickTask | DropTask | ThrowTask


class Expectations(_Strict):
    no_fall: bool | None = None
    max_completion_time: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = None
    max_torque_ratio: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = None
    max_yaw_difference: Annotated[float, Field(ge=0.0, allow_inf_nan=False)] | None = None
    placed: dict[str, str] | None = None


class Scenario(_Strict):
    """A validated task script. `source_text` and `source_path` keep the file for the logs."""

    version: Literal[1]
    name: Annotated[str, Field(min_length=1, max_length=200)]
    description: str | None = None
    robot: str = "hector"
    robot_start: RobotStart = RobotStart()
    strategy: Literal["dynamic", "quasi-static"] = "dynamic"
    model: Literal["external-force", "combined"] = "external-force"
    mpc: MpcSettings = MpcSettings()
    gait: GaitSettings = GaitSettings()
    objects: dict[str, ObjectSpec] = {}
    fixtures: dict[str, FixtureSpec] = {}
    tasks: Annotated[list[Task], Field(min_length=1)]
    end: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = None
    expect: Expectations = Expectations()

    # Default settle time after the last task when `end` is not given (s).
    SETTLE_TIME: ClassVar[float] = 1.0

    @property
    def last_task_end(self) -> float:
        return max(t.end for t in self.tasks)

    @property
    def end_time(self) -> float:
        """When the simulation stops: `end`, or the last task's end plus the settle time."""
        return self.end if self.end is not None else self.last_task_end + self.SETTLE_TIME
