"""Errors raised by the library. They carry data; only `locoplan.cli` maps them to exit codes."""

from __future__ import annotations

from dataclasses import dataclass


class LocoplanError(Exception):
    """Base class of every error locoplan raises on purpose."""


@dataclass(frozen=True, slots=True)
class ScenarioIssue:
    """One problem in a task script, with its position (1-based line and column)."""

    path: str
    line: int
    column: int
    message: str

    def __str__(self) -> str:
        return f"{self.path}:{self.line}:{self.column}: {self.message}"


class ScenarioError(LocoplanError):
    """A task script breaks the format. Holds every issue found, in file order."""

    def __init__(self, issues: list[ScenarioIssue]) -> None:
        if not issues:
            raise ValueError("ScenarioError needs at least one issue")
        self.issues = sorted(issues, key=lambda i: (i.line, i.column))
        super().__init__("\n".join(str(i) for i in self.issues))


class RobotDescriptionError(LocoplanError):
    """A robot description (MJCF + robot.yaml) is missing or inconsistent."""


class SolverFailure(LocoplanError):
    """A QP solver failed and no fallback could recover.

    `t` is the simulation time (s), `solver` the backend, `problem` "mpc" or "wbc".
    """

    def __init__(self, t: float, problem: str, solver: str, status: str, detail: str = "") -> None:
        self.t = t
        self.problem = problem
        self.solver = solver
        self.status = status
        self.detail = detail
        msg = f"{problem.upper()} QP failed at t={t:.3f} s ({solver}: {status})"
        if detail:
            msg += f": {detail}"
        super().__init__(msg)


class SimulationError(LocoplanError):
    """The simulation became unstable (NaN state, exploding velocities)."""

    def __init__(self, t: float, detail: str) -> None:
        self.t = t
        self.detail = detail
        super().__init__(f"simulation unstable at t={t:.3f} s: {detail}")
