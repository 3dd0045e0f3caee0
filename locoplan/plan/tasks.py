"""Planned tasks: the scenario's tasks with (possibly re-timed) times, and quasi-static timing.

`plan_tasks` turns `Scenario.tasks` into `PlannedTask`s sorted by start time (file order breaks
ties), with angles in radians. `retime_quasi_static` implements the quasi-static strategy of
the scenario format: the same tasks in the same order, re-timed so that locomotion and
manipulation never overlap, keeping the gaps written in the file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Literal

from locoplan.scenario.model import (
    LOCOMOTION_ACTIONS,
    MANIPULATION_ACTIONS,
    DropTask,
    PickTask,
    Scenario,
    ThrowTask,
    TurnTask,
    WalkTask,
)

TaskKind = Literal["locomotion", "manipulation", "stand"]


@dataclass(frozen=True, slots=True)
class PlannedTask:
    """One task of the plan. Times in s from the simulation start.

    `index` is the task's position in the scenario file's task list; `start`/`end` are the
    planned (possibly re-timed) times, `shift` = planned start - start written in the file.
    Action parameters are None where they do not apply:
    `object` (pick/drop/throw), `hands` ("both" | "left" | "right": for a pick as written, for a
    drop/throw the hands that hold the object), `distance` (walk, body frame at task start, m),
    `angle` (turn, or a walk's optional yaw change; rad, counter-clockwise
    positive), `onto` / `at` (drop: fixture name / object
    centre in world, m), `velocity` (throw, body frame at release, m/s).
    """

    index: int
    action: str
    start: float
    end: float
    shift: float = 0.0
    object: str | None = None
    hands: str | None = None
    distance: tuple[float, float] | None = None
    angle: float | None = None
    onto: str | None = None
    at: tuple[float, float, float] | None = None
    velocity: tuple[float, float, float] | None = None

    @property
    def duration(self) -> float:
        """Task duration (s)."""
        return self.end - self.start

    @property
    def kind(self) -> TaskKind:
        """Task kind: "locomotion" (step, walk, turn), "manipulation" (pick, drop, throw)
        or "stand"."""
        if self.action in LOCOMOTION_ACTIONS:
            return "locomotion"
        if self.action in MANIPULATION_ACTIONS:
            return "manipulation"
        return "stand"

    def at_fraction(self, fraction: float) -> float:
        """Time (s) at `fraction` of the task's duration."""
        return self.start + fraction * (self.end - self.start)


def plan_tasks(scenario: Scenario) -> tuple[PlannedTask, ...]:
    """The scenario's tasks as `PlannedTask`s at the written times, sorted by (start, index)."""
    out: list[PlannedTask] = []
    for i, task in enumerate(scenario.tasks):
        pt = PlannedTask(index=i, action=task.action, start=task.start, end=task.end)
        if isinstance(task, WalkTask):
            pt = replace(
                pt,
                distance=(task.distance[0], task.distance[1]),
                angle=math.radians(task.angle),
            )
        elif isinstance(task, TurnTask):
            pt = replace(pt, angle=math.radians(task.angle))
        elif isinstance(task, PickTask):
            pt = replace(pt, object=task.object, hands=task.hands)
        elif isinstance(task, DropTask):
            at = None if task.at is None else (task.at[0], task.at[1], task.at[2])
            pt = replace(pt, object=task.object, onto=task.onto, at=at)
        elif isinstance(task, ThrowTask):
            v = task.velocity
            pt = replace(pt, object=task.object, velocity=(v[0], v[1], v[2]))
        out.append(pt)
    out.sort(key=lambda t: (t.start, t.index))
    return tuple(out)


def retime_quasi_static(tasks: tuple[PlannedTask, ...]) -> tuple[PlannedTask, ...]:
    """Re-time sorted tasks so that locomotion and manipulation never overlap.

    Walking the tasks in order, with shift_{i-1} the shift of the previous task:
    new_start_i = max(start_i + shift_{i-1}, latest end of the already placed tasks of the
    other kind) for locomotion and manipulation; `stand` tasks only carry the running shift.
    Shifts never decrease along the order, so the order, the durations and the gaps written in
    the file (where nothing forces a wait) are kept; the last task has the largest shift.
    """
    placed_end: dict[TaskKind, float] = {"locomotion": -math.inf, "manipulation": -math.inf}
    shift = 0.0
    out: list[PlannedTask] = []
    for task in tasks:
        start = task.start + shift
        kind = task.kind
        if kind == "locomotion":
            start = max(start, placed_end["manipulation"])
        elif kind == "manipulation":
            start = max(start, placed_end["locomotion"])
        shift = start - task.start
        moved = replace(task, start=start, end=task.end + shift, shift=shift)
        if kind in placed_end:
            placed_end[kind] = max(placed_end[kind], moved.end)
        out.append(moved)
    return tuple(out)
