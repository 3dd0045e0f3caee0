"""Errors of the plan compiler."""

from __future__ import annotations

from locoplan.exceptions import LocoplanError


class PlanError(LocoplanError):
    """A scenario cannot be compiled into a plan.

    The scenario validator (`locoplan.scenario.semantics`) rejects these cases with a file
    position first; the compiler still refuses them on its own so that a hand-built
    `Scenario` cannot produce a silently wrong plan. `task_index` is the position of the
    offending task in the scenario's task list, or None when no single task is to blame.
    """

    def __init__(self, message: str, task_index: int | None = None) -> None:
        self.task_index = task_index
        self.message = message
        where = f"task {task_index}: " if task_index is not None else ""
        super().__init__(f"{where}{message}")
