"""Plan events: the instants the controller and the logs care about."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

EventKind = Literal["task_start", "task_end", "liftoff", "touchdown", "grasp", "lift", "release"]

# Order of simultaneous events: what ends comes before what starts.
_KIND_ORDER: dict[str, int] = {
    "task_end": 0,
    "touchdown": 1,
    "release": 2,
    "task_start": 3,
    "liftoff": 4,
    "grasp": 5,
    "lift": 6,
}


@dataclass(frozen=True, slots=True)
class PlanEvent:
    """An instant of the plan: `t` (s), `kind`, the scenario task it belongs to and a detail:
    the action for task_start/task_end, the foot ("L"/"R") for liftoff/touchdown, the object's
    name for grasp/lift/release."""

    t: float
    kind: EventKind
    task_index: int
    detail: str


def sort_events(events: list[PlanEvent]) -> tuple[PlanEvent, ...]:
    """Events sorted by time, then kind (ends before starts), task index and detail."""
    return tuple(sorted(events, key=lambda e: (e.t, _KIND_ORDER[e.kind], e.task_index, e.detail)))
