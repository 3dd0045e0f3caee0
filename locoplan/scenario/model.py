"""Pydantic v2 models of the task-script format, version 1 (`shared/scenario-format.md`).

These models check types and per-field ranges only; cross-field rules (objects held,
overlapping locomotion, tasks past `end`) live in `locoplan.scenario.semantics` so that each
error can point at the exact YAML node. Angles stay in degrees here, as in the file; the plan
compiler converts to radians.

Every model is strict: a number must be written as a number (`start: "1.0"` and
`start: true` are rejected, an integer is accepted where a float is expected), a boolean as
`true`/`false`, an integer as an integer (`horizon: 20.0` is rejected).
"""

from __future__ import annotations

import math
from typing import Annotated, Any, ClassVar, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

Vec2 = Annotated[list[float], Field(min_length=2, max_length=2)]
Vec3 = Annotated[list[float], Field(min_length=3, max_length=3)]

# Finite-ness is checked for every float: YAML accepts .inf and .nan.
FiniteFloat = Annotated[float, Field(allow_inf_nan=False)]
PositiveTime = Annotated[float, Field(gt=0.0, allow_inf_nan=False)]
NonNegTime = Annotated[float, Field(ge=0.0, allow_inf_nan=False)]

# A scene's lengths (positions, sizes, walk distances, drop points) stay within a kilometre
# and its speeds (belts, throws) within 100 m/s. The format sets no bound, but a warehouse
# cell is tens of metres and nothing the robot can do is faster than a few m/s: a larger value
# is a typo (`1e308` for `1.08`) that would overflow the planner's clearance and reach
# arithmetic (squares of 1e155 and more are inf) rather than be refused by it.
MAX_LENGTH = 1000.0  # m
MAX_SPEED = 100.0  # m/s
Length = Annotated[float, Field(ge=-MAX_LENGTH, le=MAX_LENGTH, allow_inf_nan=False)]
PositiveLength = Annotated[float, Field(gt=0.0, le=MAX_LENGTH, allow_inf_nan=False)]
Speed = Annotated[float, Field(ge=-MAX_SPEED, le=MAX_SPEED, allow_inf_nan=False)]

ACTIONS = ("stand", "step", "walk", "turn", "pick", "drop", "throw")
LOCOMOTION_ACTIONS = ("step", "walk", "turn")
MANIPULATION_ACTIONS = ("pick", "drop", "throw")


class FieldValueError(ValueError):
    """A cross-field rule of one model failed; `field` names the key the error points at.

    Raised from model validators so that `locoplan.scenario.loader` can point at that key's
    value instead of at the whole mapping.
    """

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)


class RobotStart(_Strict):
    """Initial stance of the robot: trunk above `position`, facing `yaw`."""

    position: Annotated[
        list[Length],
        Field(min_length=2, max_length=2, description="[x, y] in the world frame, m"),
    ] = [0.0, 0.0]
    yaw: FiniteFloat = Field(0.0, description="heading, degrees, counter-clockwise from +x")


class MpcSettings(_Strict):
    """MPC sample time and horizon; the defaults are the paper's."""

    dt: Annotated[
        float, Field(gt=0.0, le=0.2, allow_inf_nan=False, description="sample time, s")
    ] = 0.03
    horizon: Annotated[int, Field(ge=2, le=100, description="number of MPC steps")] = 20


class GaitSettings(_Strict):
    """Stepping gait: `period` is one full cycle (left swing then right swing), `swing` the
    swing time of one foot. Double support per half cycle is period/2 - swing."""

    period: Annotated[
        float,
        Field(gt=0.0, le=5.0, allow_inf_nan=False, description="one full gait cycle, s"),
    ] = 0.4
    swing: Annotated[
        float,
        Field(gt=0.0, le=2.5, allow_inf_nan=False, description="swing time of one foot, s"),
    ] = 0.15

    @model_validator(mode="after")
    def _swing_fits(self) -> GaitSettings:
        if self.swing > self.period / 2 + 1e-12:
            raise FieldValueError(
                "swing",
                f"gait swing {self.swing:g} s is longer than half the period "
                f"({self.period / 2:g} s); allowed: 0 < swing <= period / 2",
            )
        return self


class ObjectSpec(_Strict):
    """A movable object (box or sphere)."""

    shape: Literal["box", "sphere"]
    size: Annotated[
        list[PositiveLength],
        Field(min_length=1, description="box: [x, y, z] full extents, sphere: [radius]; m"),
    ]
    mass: Annotated[float, Field(gt=0.0, le=1000.0, allow_inf_nan=False, description="mass, kg")]
    position: Annotated[
        list[Length],
        Field(min_length=3, max_length=3, description="centre [x, y, z], world frame, m"),
    ]
    yaw: FiniteFloat = Field(0.0, description="degrees, counter-clockwise")

    @model_validator(mode="after")
    def _size_matches_shape(self) -> ObjectSpec:
        want = 3 if self.shape == "box" else 1
        if len(self.size) != want:
            what = "[x, y, z] full extents" if self.shape == "box" else "[radius]"
            raise FieldValueError(
                "size",
                f"a {self.shape} needs size {what} ({want} value{'s' if want > 1 else ''}), "
                f"got {len(self.size)}",
            )
        return self


class FixtureSpec(_Strict):
    """Static scenery (table, platform) or a moving conveyor belt."""

    kind: Literal["table", "conveyor", "platform"]
    position: Annotated[
        list[Length],
        Field(
            min_length=3,
            max_length=3,
            description="centre of the footprint on the floor [x, y, z], world frame, m",
        ),
    ]
    size: Annotated[
        list[PositiveLength],
        Field(
            min_length=3,
            max_length=3,
            description="full extents [x, y, z], m; the top surface is at z = size[2]",
        ),
    ]
    yaw: FiniteFloat = Field(0.0, description="degrees, counter-clockwise")
    speed: Speed | None = Field(
        None, description="conveyor only: belt speed along its own x axis, m/s"
    )

    @model_validator(mode="after")
    def _speed_only_on_conveyor(self) -> FixtureSpec:
        if self.speed is not None and self.kind != "conveyor":
            raise FieldValueError(
                "speed", f"'speed' is allowed on a conveyor only, not on a {self.kind}"
            )
        return self

    @property
    def top_height(self) -> float:
        return self.size[2]

    def local_xy(self, x: float, y: float) -> tuple[float, float]:
        """The world point (x, y) (m) in the fixture's own frame: along its x and y axes from
        the centre of its footprint."""
        yaw = math.radians(self.yaw)
        c, s = math.cos(yaw), math.sin(yaw)
        dx, dy = x - self.position[0], y - self.position[1]
        return c * dx + s * dy, -s * dx + c * dy


class _TaskBase(_Strict):
    start: NonNegTime = Field(description="s from the beginning of the simulation")
    duration: PositiveTime = Field(description="s, how long the contact phase or motion takes")

    @property
    def end(self) -> float:
        return self.start + self.duration


class StandTask(_TaskBase):
    """Both feet in stance, no stepping."""

    action: Literal["stand"]


class StepTask(_TaskBase):
    """Step in place with the gait."""

    action: Literal["step"]


class WalkTask(_TaskBase):
    """Walk a displacement within `duration`."""

    action: Literal["walk"]
    distance: Annotated[
        list[Length],
        Field(min_length=2, max_length=2, description="[dx, dy], body frame at task start, m"),
    ]
    angle: Annotated[
        FiniteFloat,
        Field(
            description=(
                "optional yaw change while walking, degrees (a locoplan addition to format v1:"
                " walk while turning); the path is the straight line of `distance`"
            )
        ),
    ] = 0.0


class TurnTask(_TaskBase):
    """Turn in place by a yaw change within `duration`, stepping."""

    action: Literal["turn"]
    angle: FiniteFloat = Field(description="yaw change, degrees, counter-clockwise positive")


class PickTask(_TaskBase):
    """Reach, make hand contact and lift the object to the carry pose."""

    action: Literal["pick"]
    object: str = Field(description="name of a declared object")
    hands: Literal["both", "left", "right"] = "both"


class DropTask(_TaskBase):
    """Place the held object on a fixture (`onto`) or at a point (`at`) and release it."""

    action: Literal["drop"]
    object: str = Field(description="name of the held object")
    onto: str | None = Field(None, description="name of a declared fixture")
    at: Annotated[list[Length], Field(min_length=3, max_length=3)] | None = Field(
        None, description="object centre [x, y, z], world frame, m"
    )

    @model_validator(mode="after")
    def _one_target(self) -> DropTask:
        if self.onto is not None and self.at is not None:
            raise FieldValueError(
                "at",
                "a drop needs exactly one target: 'onto: FIXTURE' or 'at: [x, y, z]', not both",
            )
        if self.onto is None and self.at is None:
            raise ValueError("a drop needs exactly one target: 'onto: FIXTURE' or 'at: [x, y, z]'")
        return self


class ThrowTask(_TaskBase):
    """Swing and release the held object with a velocity."""

    action: Literal["throw"]
    object: str = Field(description="name of the held object")
    velocity: Annotated[
        list[Speed],
        Field(min_length=3, max_length=3, description="release velocity, body frame, m/s"),
    ]


Task = Annotated[
    StandTask | StepTask | WalkTask | TurnTask | PickTask | DropTask | ThrowTask,
    Field(discriminator="action"),
]
ManipulationTask = PickTask | DropTask | ThrowTask


class Expectations(_Strict):
    """Pass/fail checks used by `run` (exit code) and `batch`."""

    no_fall: bool | None = Field(None, description="the trunk never drops below its fall height")
    max_completion_time: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = Field(
        None, description="s, when the last task's goal is met"
    )
    max_torque_ratio: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = Field(
        None, description="peak |tau| / limit over every joint"
    )
    max_yaw_difference: Annotated[float, Field(ge=0.0, allow_inf_nan=False)] | None = Field(
        None, description="deg, |yaw at drop start - yaw at pick start|"
    )
    placed: dict[str, str] | None = Field(
        None, description="object name -> fixture name it must rest on at the end"
    )


class Scenario(_Strict):
    """A validated task script (format version 1).

    The file's text and path are not part of the model: `load_scenario_file` returns them
    next to it in a `LoadedScenario`.
    """

    version: Literal[1] = Field(description="format version, must be 1")
    name: Annotated[
        str,
        Field(min_length=1, max_length=200, description="short identifier, used in logs"),
    ]
    description: str | None = Field(None, description="free text")
    robot: str = Field(
        "hector",
        description=(
            "'hector' or 'h1', or a path to a robot file (.yaml or .xml) relative to the script"
        ),
    )
    robot_start: RobotStart = RobotStart()
    strategy: Literal["dynamic", "quasi-static"] = Field(
        "dynamic", description="how tasks are scheduled"
    )
    model: Literal["external-force", "combined"] = Field(
        "external-force", description="SRBD used by the MPC: the paper's Model 2 or Model 1"
    )
    mpc: MpcSettings = MpcSettings()
    gait: GaitSettings = GaitSettings()
    objects: dict[str, ObjectSpec] = Field({}, description="movable objects by name")
    fixtures: dict[str, FixtureSpec] = Field({}, description="scenery by name")
    tasks: Annotated[list[Task], Field(min_length=1, description="what the robot does")]
    end: Annotated[float, Field(gt=0.0, allow_inf_nan=False)] | None = Field(
        None, description="s, when the simulation stops; default: last task's end + settle time"
    )
    expect: Expectations = Expectations()

    # Default settle time after the last task when `end` is not given (s).
    SETTLE_TIME: ClassVar[float] = 1.0

    @field_validator("version", mode="before")
    @classmethod
    def _version_is_int(cls, value: Any) -> Any:
        # Literal[1] alone accepts `true` and `1.0` (both compare equal to 1).
        if isinstance(value, bool | float):
            raise ValueError("version must be the integer 1")
        return value

    @property
    def last_task_end(self) -> float:
        return max(t.end for t in self.tasks)

    @property
    def end_time(self) -> float:
        """When the simulation stops: `end`, or the last task's end plus the settle time."""
        return self.end if self.end is not None else self.last_task_end + self.SETTLE_TIME
