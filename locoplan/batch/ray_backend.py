"""Ray backend: the same jobs as Ray tasks, on an existing cluster or a local Ray.

Used by `locoplan sweep --backend ray` and `locoplan batch --backend ray`. Each job is one task
(`num_cpus=1`, no retries) running `execute_job`, the function the local workers run, so a
script or a point gives the same metrics on either backend. At most `workers` tasks are in
flight, so `--jobs` bounds the cluster share a run takes. A task whose worker dies is that
job's error; one past `timeout` is cancelled (forcefully: its worker is killed); one on a node
whose locoplan code or library versions differ from the driver's (`cache.code_fingerprint`)
is an error saying so, rather than results of other code. Workers write their MCAP logs on
their own node, where the driver's working directory may not exist: the jobs' paths are made
absolute before they are sent, and on a cluster `--out` should be on a filesystem every node
mounts. Ray reports no per-tick progress, only starts and ends.
"""

from __future__ import annotations

import functools
import logging
import socket
import time
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from locoplan import interrupt
from locoplan.batch.errors import BackendUnavailable
from locoplan.batch.job import Job, Outcome, RunListener
from locoplan.batch.worker import execute_job

INSTALL_HINT = "pip install 'locoplan[ray]'"
# Seconds between two checks of the tasks in flight for a timeout.
POLL_INTERVAL = 0.5
# Seconds to wait for a TCP connection to a cluster's address before saying it is unreachable
# (Ray itself retries for minutes, in native code that signals cannot interrupt).
CONNECT_TIMEOUT = 5.0
# Seconds the tasks get to close their MCAP logs after a signal before they are killed.
TERMINATE_GRACE = 3.0


def import_ray() -> Any:
    """The `ray` module, or BackendUnavailable saying how to install it."""
    try:
        import ray
    except ImportError as exc:
        raise BackendUnavailable(
            "ray", f"the Ray backend needs Ray, which is not installed ({exc})", INSTALL_HINT
        ) from None
    return ray


def workers_for(n_jobs: int, workers: int | None, address: str | None) -> int:
    """Tasks in flight at most: `workers` (`--jobs`) if given; else every job at once on a
    cluster (Ray schedules them on its free CPUs), or one per local core for a local Ray."""
    if workers is not None:
        return max(1, workers)
    if address is not None:
        return max(1, n_jobs)
    from locoplan.batch.pool import default_workers

    return default_workers()


def check_reachable(address: str, timeout: float = CONNECT_TIMEOUT) -> None:
    """Raise BackendUnavailable when `address` (`HOST:PORT` or `ray://HOST:PORT`) accepts no
    TCP connection within `timeout` seconds; other forms (`auto`) are left to Ray."""
    rest = address.removeprefix("ray://")
    host, sep, port = rest.rpartition(":")
    if not sep or not host or not port.isdigit() or "/" in rest:
        return
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout).close()
    except OSError as exc:
        raise BackendUnavailable(
            "ray",
            f"cannot reach the Ray cluster at {address}: {exc.strerror or exc}",
            "is 'ray start --head' running there, and is the port right (6379 for HOST:PORT, "
            "10001 for ray://HOST:PORT)?",
        ) from None


@functools.cache
def _worker_code() -> str:
    from locoplan.batch.cache import code_fingerprint

    return code_fingerprint()


def _execute(job: Job, code: str | None = None) -> Outcome:
    """A Ray task: `execute_job`, after checking that this node runs the driver's code
    (`code`: the driver's `code_fingerprint()`, None to skip the check)."""
    if code is not None and _worker_code() != code:
        message = (
            f"the Ray worker on {socket.gethostname()} runs other locoplan code or library "
            f"versions than the driver (code fingerprint {_worker_code()[:12]}, driver "
            f"{code[:12]}); install the same locoplan and dependencies on every node"
        )
        return Outcome(job.job_id, "error", message=message)
    return execute_job(job)


def run_ray(
    jobs: Sequence[Job],
    workers: int,
    address: str | None = None,
    timeout: float | None = None,
    listener: RunListener | None = None,
    fail_fast: bool = False,
) -> list[Outcome]:
    """Run `jobs` as Ray tasks and return their outcomes in the order of `jobs`.

    `address` is an existing cluster (`ray://host:10001`, `host:6379`, or `auto`); None starts
    a local Ray with `workers` CPUs for this call and shuts it down after. With `fail_fast`,
    the first job that does not pass cancels the tasks in flight and those not started, all
    reported as `skipped` (as `pool.run_local` does). Raises BackendUnavailable when Ray is
    missing or the cluster cannot be reached.
    """
    if workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    ray = import_ray()
    started_here = False
    if not ray.is_initialized():
        if address is not None:
            check_reachable(address)
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
        return _run(ray, jobs, workers, timeout, listener, fail_fast)
    finally:
        if started_here:
            ray.shutdown()


def _run(
    ray: Any,
    jobs: Sequence[Job],
    workers: int,
    timeout: float | None,
    listener: RunListener | None,
    fail_fast: bool = False,
) -> list[Outcome]:
    from locoplan.batch.cache import code_fingerprint

    remote = ray.remote(num_cpus=1, max_retries=0)(_execute)
    code = code_fingerprint()
    pending = list(jobs)
    pending.reverse()
    in_flight: dict[Any, tuple[Job, float]] = {}
    outcomes: dict[str, Outcome] = {}
    stopping = False

    def finish(outcome: Outcome) -> None:
        nonlocal stopping
        outcomes[outcome.job_id] = outcome
        if listener is not None:
            listener.finished(outcome)
        if fail_fast and outcome.status in ("failed", "error"):
            stopping = True

    try:
        # A SIGINT / SIGTERM only sets locoplan.interrupt's flag here (the CLI installs its
        # handlers): raised inside Ray's wait, it came out as a bare SystemExit(1).
        with interrupt.deferring():
            while pending or in_flight:
                signum = interrupt.pending()
                if signum:
                    _stop_in_flight(ray, in_flight, finish, signum)
                    why = f"not run (interrupted, {interrupt.signal_name(signum)})"
                    while pending:
                        finish(Outcome(pending.pop().job_id, "skipped", message=why))
                    break
                if stopping:
                    for ref, (job, _) in list(in_flight.items()):
                        ray.cancel(ref, force=True)
                        del in_flight[ref]
                        finish(Outcome(job.job_id, "skipped", message="stopped (--fail-fast)"))
                    while pending:
                        job = pending.pop()
                        finish(Outcome(job.job_id, "skipped", message="not run (--fail-fast)"))
                    break
                while pending and len(in_flight) < workers:
                    job = pending.pop()
                    in_flight[remote.remote(_absolute(job), code)] = (job, time.monotonic())
                    if listener is not None:
                        listener.started(job)
                ready, _ = ray.wait(list(in_flight), num_returns=1, timeout=POLL_INTERVAL)
                for ref in ready:
                    job, started = in_flight.pop(ref)
                    finish(_collect(ray, ref, job, started))
                if timeout is not None:
                    _cancel_late(ray, in_flight, finish, timeout)
    except BaseException:
        for ref in in_flight:
            ray.cancel(ref, force=True)
        raise
    return [outcomes[job.job_id] for job in jobs]


def _collect(ray: Any, ref: Any, job: Job, started: float) -> Outcome:
    """The outcome of a finished task; a task that failed in Ray (its worker died, it was
    cancelled) is the job's error."""
    try:
        return _as_given(ray.get(ref), job)
    except ray.exceptions.RayError as exc:
        message = f"Ray task failed: {type(exc).__name__}: {_first_line(exc)}"
        return Outcome(job.job_id, "error", message=message, wall_time=time.monotonic() - started)


def _cancel_late(
    ray: Any, in_flight: dict[Any, tuple[Job, float]], finish: Any, timeout: float
) -> None:
    """Cancel (forcefully) every task running longer than `timeout` s: that job's error."""
    now = time.monotonic()
    for ref, (job, started) in list(in_flight.items()):
        if now - started > timeout:
            ray.cancel(ref, force=True)
            del in_flight[ref]
            message = f"timed out after {timeout:g} s (--timeout); Ray task cancelled"
            finish(Outcome(job.job_id, "error", message=message, wall_time=now - started))


def _stop_in_flight(
    ray: Any, in_flight: dict[Any, tuple[Job, float]], finish: Any, signum: int
) -> None:
    """After a signal: cancel the running tasks (a KeyboardInterrupt in each, so its MCAP log
    is closed), give them `TERMINATE_GRACE` s, then cancel the rest forcefully. A task that
    had finished keeps its outcome; the others are `skipped`, "interrupted"."""
    refs = list(in_flight)
    for ref in refs:
        ray.cancel(ref, force=False)
    done, late = (
        ray.wait(refs, num_returns=len(refs), timeout=TERMINATE_GRACE) if refs else ([], [])
    )
    for ref in late:
        ray.cancel(ref, force=True)
    name = interrupt.signal_name(signum)
    for ref in refs:
        job, started = in_flight.pop(ref)
        outcome = _collect(ray, ref, job, started) if ref in done else None
        if outcome is None or outcome.status == "error":
            log = Path(job.options.out_dir) / f"{job.options.log_name or job.name}.mcap"
            message = f"interrupted ({name}); Ray task cancelled, log up to there: {log}"
            outcome = Outcome(job.job_id, "skipped", message=message,
                              wall_time=time.monotonic() - started)  # fmt: skip
        finish(outcome)


def _absolute(job: Job) -> Job:
    """`job` with its script path and output folder absolute: a Ray worker's working
    directory is not the driver's (on a cluster, not even on the same machine)."""
    options = replace(job.options, out_dir=Path(job.options.out_dir).absolute())
    return replace(job, source=str(Path(job.source).absolute()), options=options)


def _as_given(outcome: Outcome, job: Job) -> Outcome:
    """The outcome with its metrics' `log` path spelled as the job gave it (relative when the
    command line was), as the local backend reports it."""
    metrics = outcome.metrics
    if metrics is None or not isinstance(metrics.get("log"), str):
        return outcome
    name = job.options.log_name or job.name
    given = Path(job.options.out_dir) / f"{name}.mcap"
    if Path(metrics["log"]) != given.absolute():
        return outcome
    return replace(outcome, metrics={**metrics, "log": str(given)})


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else ""
