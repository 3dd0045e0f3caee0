"""Local backend: each job in its own worker process, at most `workers` at a time.

A fresh process per job isolates runs from each other: a worker that dies (a segfault in a
native solver, `os._exit`) or hangs (killed after `timeout`) costs only its own job, and no
state leaks from one run into the next. Processes come from multiprocessing's `forkserver`
(the server imports the simulator once, so each worker starts in milliseconds instead of the
~1.5 s of importing MuJoCo, pinocchio and the solvers) or `spawn` where forkserver does not
exist. `concurrent.futures.ProcessPoolExecutor` is not used: one dead worker breaks the whole
executor, and it cannot kill a single hung task.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import time
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from multiprocessing.connection import Connection, wait
from multiprocessing.context import BaseContext
from typing import Any

from locoplan import interrupt
from locoplan.batch.job import Job, Outcome, RunListener
from locoplan.batch.worker import execute_job

# Seconds between two progress messages of one worker: enough for a live display, few
# enough that the pipe never fills.
PROGRESS_INTERVAL = 0.25
# Seconds a worker gets to close its MCAP log after SIGTERM before it is killed.
TERMINATE_GRACE = 3.0
# Seconds between two checks of the running workers for a timeout.
POLL_INTERVAL = 0.2

_PRELOAD = ["locoplan.batch.worker", "locoplan.sim.run"]


def default_workers() -> int:
    """One worker per core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, multiprocessing.cpu_count())


def _context() -> BaseContext:
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        ctx.set_forkserver_preload(_PRELOAD)
        return ctx
    return multiprocessing.get_context("spawn")


def _child_main(job: Job, conn: Connection) -> None:
    """Entry point of a worker process: run `job`, send progress and the outcome."""
    # SIGTERM (a timeout, the parent stopping, a user) or SIGINT (Ctrl-C reaches the whole
    # process group) stops the run at its next control tick: the MCAP is closed whole and the
    # process exits with 128 + signal, without a traceback.
    interrupt.install_for_worker()
    last = 0.0

    def progress(t: float, total: float) -> None:
        nonlocal last
        now = time.monotonic()
        if now - last >= PROGRESS_INTERVAL:
            last = now
            conn.send(("progress", t, total))

    try:
        outcome = execute_job(job, progress)
        conn.send(("done", outcome))
    except KeyboardInterrupt:
        # Ctrl-C reaches the whole process group; the parent reports it. Leaving quietly
        # (the MCAP was closed on the way out) keeps multiprocessing from printing a traceback.
        raise SystemExit(130) from None
    finally:
        conn.close()


@dataclass(slots=True)
class _Running:
    job: Job
    process: Any  # multiprocessing.process.BaseProcess (the context's Process type)
    conn: Connection
    started: float
    sim_time: float = 0.0
    outcome: Outcome | None = None
    closed: bool = False


def _describe_death(exitcode: int | None) -> str:
    if exitcode is None:
        return "worker vanished"
    if exitcode < 0:
        try:
            return f"worker died (killed by {signal.Signals(-exitcode).name})"
        except ValueError:
            return f"worker died (killed by signal {-exitcode})"
    if exitcode in (130, 143):  # a worker stopped by SIGINT / SIGTERM (not from us)
        return f"worker stopped by {interrupt.signal_name(exitcode - 128)} (log closed)"
    return f"worker died (exit status {exitcode})"


def _stop_all(processes: Sequence[Any], grace: float = TERMINATE_GRACE) -> None:
    """`_stop` for several workers at once: SIGTERM to all, then the same grace for all."""
    for process in processes:
        if process.is_alive():
            process.terminate()
    deadline = time.monotonic() + grace
    for process in processes:
        process.join(max(0.0, deadline - time.monotonic()))
    for process in processes:
        if process.is_alive():
            process.kill()
            process.join()


def _interrupted_outcome(run: _Running, signum: int) -> Outcome:
    log = run.job.options.out_dir / f"{run.job.options.log_name or run.job.name}.mcap"
    message = (
        f"interrupted ({interrupt.signal_name(signum)}) at t={run.sim_time:.2f} s simulated;"
        f" log up to there: {log}"
    )
    return Outcome(run.job.job_id, "skipped", message=message,
                   wall_time=time.monotonic() - run.started)  # fmt: skip


def _stop(process: Any, grace: float = TERMINATE_GRACE) -> None:
    """SIGTERM (the worker closes its log), then SIGKILL if it has not exited after `grace`."""
    if process.is_alive():
        process.terminate()
        process.join(grace)
    if process.is_alive():
        process.kill()
        process.join()


def run_local(
    jobs: Sequence[Job],
    workers: int | None = None,
    timeout: float | None = None,
    listener: RunListener | None = None,
    fail_fast: bool = False,
) -> list[Outcome]:
    """Run `jobs` in worker processes, at most `workers` (default: one per core) at a time,
    and return their outcomes in the order of `jobs`.

    A job whose worker runs longer than `timeout` seconds (None: no limit) is stopped and
    becomes an `error`, as does one whose worker dies. With `fail_fast`, the first job that
    does not pass stops the others: running ones are stopped and, like those not started,
    reported as `skipped`. A SIGINT / SIGTERM deferred by `locoplan.interrupt` (the CLI
    installs its handlers) stops every worker the same way, each closing its log: the
    running jobs and those not started are `skipped` ("interrupted ..."), and the outcomes
    are returned (`locoplan.interrupt.pending()` tells the caller). KeyboardInterrupt (no
    handlers installed) stops every worker, then propagates.
    """
    if workers is not None and workers < 1:
        raise ValueError(f"workers must be at least 1, got {workers}")
    if timeout is not None and not timeout > 0:
        raise ValueError(f"timeout must be positive, got {timeout}")
    if len({job.job_id for job in jobs}) != len(jobs):
        raise ValueError("job ids must be unique")
    n_workers = workers or default_workers()
    ctx = _context()
    pending = deque(jobs)
    running: list[_Running] = []
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
        with interrupt.deferring():
            while pending or running:
                while pending and len(running) < n_workers and not stopping:
                    job = pending.popleft()
                    receiver, sender = ctx.Pipe(duplex=False)
                    process = ctx.Process(  # type: ignore[attr-defined]
                        target=_child_main,
                        args=(job, sender),
                        name=f"locoplan-worker {job.job_id}",
                        daemon=True,
                    )
                    process.start()
                    sender.close()  # the child holds the only writer: EOF means it is gone
                    running.append(_Running(job, process, receiver, time.monotonic()))
                    if listener is not None:
                        listener.started(job)
                signum = interrupt.pending()
                if signum:
                    # Every worker stops at its next control tick (its log closed whole).
                    _stop_all([run.process for run in running])
                    for run in running:
                        _drain(run, listener)  # an outcome sent just before the signal
                        run.conn.close()
                        finish(run.outcome or _interrupted_outcome(run, signum))
                    running.clear()
                    why = f"not run (interrupted, {interrupt.signal_name(signum)})"
                    for job in pending:
                        finish(Outcome(job.job_id, "skipped", message=why))
                    pending.clear()
                    break
                if stopping:
                    for run in running:
                        _stop(run.process)
                        run.conn.close()
                        finish(Outcome(run.job.job_id, "skipped", message="stopped (--fail-fast)"))
                    running.clear()
                    for job in pending:
                        finish(Outcome(job.job_id, "skipped", message="not run (--fail-fast)"))
                    pending.clear()
                    break
                waitables: list[Any] = [r.conn for r in running if not r.closed]
                waitables += [r.process.sentinel for r in running]
                wait(waitables, timeout=POLL_INTERVAL)
                still: list[_Running] = []
                for run in running:
                    done = _poll(run, listener, timeout)
                    if done is None:
                        still.append(run)
                    else:
                        finish(done)
                running = still
    except BaseException:
        _stop_all([run.process for run in running], grace=1.0)
        raise
    return [outcomes[job.job_id] for job in jobs]


def _drain(run: _Running, listener: RunListener | None) -> None:
    """Read every message the worker has sent so far."""
    while not run.closed:
        try:
            if not run.conn.poll():
                return
            message = run.conn.recv()
        except (EOFError, OSError):
            run.closed = True
            run.conn.close()
            return
        if message[0] == "progress":
            run.sim_time = float(message[1])
            if listener is not None:
                listener.progress(run.job, float(message[1]), float(message[2]))
        elif message[0] == "done":
            run.outcome = message[1]


def _poll(run: _Running, listener: RunListener | None, timeout: float | None) -> Outcome | None:
    """The job's outcome if it has ended (finished, died or timed out), else None."""
    _drain(run, listener)
    if run.outcome is not None:
        run.process.join(TERMINATE_GRACE)
        if run.process.is_alive():  # sent its outcome but does not exit: not our problem
            _stop(run.process)
        with contextlib.suppress(OSError):
            run.conn.close()
        return run.outcome
    elapsed = time.monotonic() - run.started
    if not run.process.is_alive():
        _drain(run, listener)  # it may have sent its outcome just before exiting
        if run.outcome is not None:
            return run.outcome
        run.process.join()
        with contextlib.suppress(OSError):
            run.conn.close()
        message = f"{_describe_death(run.process.exitcode)} at t={run.sim_time:.2f} s simulated"
        return Outcome(run.job.job_id, "error", message=message, wall_time=elapsed)
    if timeout is not None and elapsed > timeout:
        _stop(run.process)
        with contextlib.suppress(OSError):
            run.conn.close()
        message = (
            f"timed out after {timeout:g} s (--timeout) at t={run.sim_time:.2f} s simulated; "
            "worker stopped"
        )
        return Outcome(run.job.job_id, "error", message=message, wall_time=elapsed)
    return None
