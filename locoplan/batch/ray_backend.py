"""Ray backend: the same jobs as Ray tasks, on an existing cluster or a local Ray.

Each job is one task (`num_cpus=1`, no retries) running `execute_job`, the function the local
workers run, so a point gives the same metrics on either backend. At most `workers` tasks are
in flight, so `--jobs` bounds the cluster share a sweep takes. A task whose worker dies is
that job's error; one past `timeout` is cancelled (forcefully: its worker is killed). Workers
write their MCAP logs on their own node: on a cluster, point `--out` at a shared filesystem
to collect them. Ray reports no per-tick progress, only starts and ends.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from typing import Any

from locoplan.batch.errors import BackendUnavailable
from locoplan.batch.job import Job, Outcome, RunListener
from locoplan.batch.worker import execute_job

INSTALL_HINT = "pip install 'locoplan[ray]'"
# Seconds between two checks of the tasks in flight for a timeout.
POLL_INTERVAL = 0.5


def import_ray() -> Any:
    """The `ray` module, or BackendUnavailable saying how to install it."""
    try:
        import ray
    except ImportError as exc:
        raise BackendUnavailable(
            "ray", f"the Ray backend needs Ray, which is not installed ({exc})", INSTALL_HINT
        ) from None
    return ray


def _execute(job: Job) -> Outcome:
    return execute_job(job)


def run_ray(
    jobs: Sequence[Job],
    workers: int,
    address: str | None = None,
    timeout: float | None = None,
    listener: RunListener | None = None,
) -> list[Outcome]:
    """Run `jobs` as Ray tasks and return their outcomes in the order of `jobs`.

    `address` is an existing cluster (`ray://host:10001`, `host:6379`, or `auto`); None starts
    a local Ray with `workers` CPUs for this call and shuts it down after. Raises
    BackendUnavailable when Ray is missing or the cluster cannot be reached.
    """
    if workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    ray = import_ray()
    started_here = False
    if not ray.is_initialized():
        try:
            if address is not None:
                ray.init(address=address, logging_level=logging.WARNING, log_to_driver=False)
            else:
                ray.init(
                    num_cpus=workers,
                    include_dashboard=False,
                    logging_level=logging.WARNING,
                    log_to_driver=False,
                )
        except (ConnectionError, RuntimeError, ValueError) as exc:
            where = address or "a local Ray"
            raise BackendUnavailable("ray", f"cannot start or reach {where}: {exc}") from None
        started_here = True
    try:
        return _run(ray, jobs, workers, timeout, listener)
    finally:
        if started_here:
            ray.shutdown()


def _run(
    ray: Any,
    jobs: Sequence[Job],
    workers: int,
    timeout: float | None,
    listener: RunListener | None,
) -> list[Outcome]:
    remote = ray.remote(num_cpus=1, max_retries=0)(_execute)
    pending = list(jobs)
    pending.reverse()
    in_flight: dict[Any, tuple[Job, float]] = {}
    outcomes: dict[str, Outcome] = {}

    def finish(outcome: Outcome) -> None:
        outcomes[outcome.job_id] = outcome
        if listener is not None:
            listener.finished(outcome)

    try:
        while pending or in_flight:
            while pending and len(in_flight) < workers:
                job = pending.pop()
                in_flight[remote.remote(job)] = (job, time.monotonic())
                if listener is not None:
                    listener.started(job)
            ready, _ = ray.wait(list(in_flight), num_returns=1, timeout=POLL_INTERVAL)
            for ref in ready:
                job, started = in_flight.pop(ref)
                try:
                    finish(ray.get(ref))
                except ray.exceptions.RayError as exc:
                    message = f"Ray task failed: {type(exc).__name__}: {_first_line(exc)}"
                    elapsed = time.monotonic() - started
                    finish(Outcome(job.job_id, "error", message=message, wall_time=elapsed))
            if timeout is None:
                continue
            now = time.monotonic()
            for ref, (job, started) in list(in_flight.items()):
                if now - started > timeout:
                    ray.cancel(ref, force=True)
                    del in_flight[ref]
                    message = f"timed out after {timeout:g} s (--timeout); Ray task cancelled"
                    finish(Outcome(job.job_id, "error", message=message, wall_time=now - started))
    except BaseException:
        for ref in in_flight:
            ray.cancel(ref, force=True)
        raise
    return [outcomes[job.job_id] for job in jobs]


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else ""
