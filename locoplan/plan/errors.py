"""Errors of the plan compiler."""

from __future__ import annotations

from collections.abc import Hashable

from locoplan.exceptions import LocoplanError


class PlanError(LocoplanError):
    """A scenario cannot be compiled into a plan.

    The scenario validator (`locoplan.scenario.semantics`) rejects these cases with a file
    position first; the compiler still refuses them on its own so that a hand-built
    `Scenario` cannot produce a silently wrong plan. `task_index` is the position of the
    offending task in the scenario's task list, or None when no single task is to blame.
    `loc`, when given, is the document path of the node to blame (`("tasks", 2)`; see
    `locoplan.scenario.messages`), so that commands can report `file:line:column`
    (`plan_error_message`).
    """

    def __init__(
        self,
        message: str,
        task_index: int | None = None,
        *,
        loc: tuple[Hashable, ...] | None = None,
    ) -> None:
        self.task_index = task_index
        self.message = message
        self.loc = loc
        where = f"task {task_index}: " if task_index is not None else ""
        super().__init__(f"{where}{message}")


class InfeasiblePlanError(PlanError):
    """A plan the robot cannot carry out, found without simulating (`locoplan.plan.payload`):
    the message starts `infeasible (<reason>):` as the scenario's feasibility findings do,
    and `loc` names the task to blame. `excess` (m), where set: how far past its limit the
    measured value lies (a reach refusal's grip points beyond the allowed miss)."""

    excess: float | None = None


def plan_error_message(exc: PlanError, source: str, text: str) -> str:
    """How commands report `exc` for the script `source` ("-": standard input) of text
    `text`: `file:line:column: message` when the error names its node (`loc`), else
    `file: cannot plan: ...`."""
    from locoplan.scenario.loader import locate_issue
    from locoplan.scenario.messages import LocatedIssue

    if exc.loc is None:
        shown = "<stdin>" if source == "-" else source
        return f"{shown}: cannot plan: {exc}"
    return str(locate_issue(source, text, LocatedIssue(exc.loc, exc.message)))
