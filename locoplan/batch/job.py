"""What a worker runs (`Job`) and what comes back (`Outcome`); both cross process boundaries
(pickled to a worker process or a Ray task), so they hold plain data only."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal, Protocol

from locoplan.sim.run import RunOptions

Status = Literal["passed", "failed", "error", "skipped"]
STATUSES: tuple[Status, ...] = ("passed", "failed", "error", "skipped")


@dataclass(frozen=True, slots=True)
class Job:
    """One closed-loop run to do.

    `job_id` identifies it in reports (a script's path, or a sweep point); `name` is the
    scenario's name; `source` is the script's path (it locates a robot file given by a
    relative path; for a sweep point, the swept file); `text` is the exact script to run
    (re-validated in the worker); `options.out_dir` / `options.log_name` say where its MCAP
    goes.
    """

    job_id: str
    name: str
    source: str
    text: str
    options: RunOptions


@dataclass(frozen=True, slots=True)
class Outcome:
    """How one job ended.

    `status`: passed (ran, every expectation held), failed (ran, an expectation failed),
    error (did not finish: bad script, broken run, crashed or timed-out worker), skipped
    (not started: `--fail-fast`). `metrics` is the run's metrics object (cli-contract.md)
    or None; `message` says what went wrong in one line; `detail` is longer text for
    reports (a traceback of an internal error); `wall_time` (s) is the worker's time,
    process start-up included; `cached` is True when served from the result cache.
    """

    job_id: str
    status: Status
    metrics: Mapping[str, Any] | None = None
    message: str = ""
    detail: str = ""
    wall_time: float = 0.0
    cached: bool = False

    @property
    def failures(self) -> tuple[str, ...]:
        """The failed expectations, one line each (`max_torque_ratio: 0.13 > 0.001`)."""
        if self.metrics is None:
            return ()
        return failed_expectations(self.metrics)


def _show(value: Any) -> str:
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


_LIMIT_WORDS = {
    "no_fall": "fell",
    "max_completion_time": "completion time",
    "max_torque_ratio": "peak torque ratio",
    "max_yaw_difference": "yaw difference",
}


def failed_expectations(metrics: Mapping[str, Any]) -> tuple[str, ...]:
    """Each failed expectation of a metrics object as one line, in the script's order:
    `no_fall: fell`, `max_torque_ratio: peak torque ratio 0.13 > limit 0.001`,
    `placed.package: on table, expected conveyor`, `max_completion_time: not completed`."""
    lines = []
    for key, result in metrics.get("expectations", {}).items():
        if result.get("ok", True):
            continue
        value, limit = result.get("value"), result.get("limit")
        if key == "no_fall":
            lines.append(f"{key}: fell" + _fall_time(metrics))
        elif key.startswith("placed."):
            lines.append(f"{key}: on {_show(value)}, expected {_show(limit)}")
        elif value is None:
            lines.append(f"{key}: never reached (limit {_show(limit)})")
        else:
            word = _LIMIT_WORDS.get(key, "value")
            lines.append(f"{key}: {word} {_show(value)} > limit {_show(limit)}")
    return tuple(lines)


def _fall_time(metrics: Mapping[str, Any]) -> str:
    t = metrics.get("fall_time")
    return f" at t={t:.2f} s" if isinstance(t, int | float) else ""


class RunListener(Protocol):
    """What a backend reports while it works (the CLI draws its progress display from it).
    Called from the thread that called the backend; `progress` at most a few times a second
    per job, and not at all by backends that cannot report it (Ray)."""

    def started(self, job: Job) -> None: ...

    def progress(self, job: Job, t: float, total: float) -> None: ...

    def finished(self, outcome: Outcome) -> None: ...
