"""Run several variants of one script, in parallel processes when there are cores.

Each variant runs in its own process (`ProcessPoolExecutor` with the "spawn" start method:
MuJoCo, pinocchio and the QP solvers are not fork-safe once initialised) and sends back a
`VariantOutcome` of plain data: the metrics, a `RunTrace` for the plots, or the error of a
run that broke. Progress travels from the workers through a queue as
(label, simulated time, total) and reaches the caller's callback in the parent process.
With one job the variants run one after the other in the calling process.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import queue
import signal
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from locoplan import interrupt
from locoplan.compare.trace import RunTrace, trace_from_run
from locoplan.compare.variants import Variant
from locoplan.exceptions import SimulationError, SolverFailure
from locoplan.robot.description import load_robot_description
from locoplan.scenario import Scenario
from locoplan.sim.live import LiveView
from locoplan.sim.run import RunOptions, run_scenario

# (label, simulated time s, total s) for each progress report.
VariantProgress = Callable[[str, float, float], None]
PROGRESS_PERIOD = 0.1  # s of simulated time between progress messages from a worker
POLL_PERIOD = 0.1  # s of wall time between progress polls in the parent


@dataclass(frozen=True, slots=True, eq=False)
class VariantOutcome:
    """The result of one variant: `metrics` (the contract's metrics object) and `trace`
    (plot series) when the run finished or fell; `error` (a message naming the time and the
    solver or instability) when it broke, with `log_path` the partial MCAP log."""

    variant: Variant
    metrics: dict[str, Any] | None
    trace: RunTrace | None
    error: str | None
    log_path: Path | None

    @property
    def label(self) -> str:
        """The variant's label ("quasi-static", "dynamic", "external-force", "combined")."""
        return self.variant.label

    @property
    def broke(self) -> bool:
        """Whether the run itself broke (solver failure, simulator instability)."""
        return self.error is not None

    @property
    def passed(self) -> bool:
        """Whether the run finished and every expectation of the script held."""
        return self.metrics is not None and bool(self.metrics.get("passed"))


@dataclass(frozen=True, slots=True)
class _Job:
    scenario: Scenario
    text: str
    variant: Variant
    out_dir: Path
    qp_backend: str
    live: LiveView | None = None


# Set in worker processes only (by `_init_worker`): where progress messages go.
_worker_queue: Any = None


def _init_worker(progress_queue: Any) -> None:
    global _worker_queue
    _worker_queue = progress_queue
    # Ctrl-C in a terminal reaches every process of the group, and the parent stops its
    # workers with SIGINT: either stops the run at its next control tick, its log closed.
    interrupt.install_for_worker()


def _queue_progress(label: str) -> Callable[[float, float], None]:
    last = [-1.0]

    def report(t: float, total: float) -> None:
        if _worker_queue is not None and (t - last[0] >= PROGRESS_PERIOD or t >= total):
            last[0] = t
            with contextlib.suppress(Exception):  # progress is best effort
                _worker_queue.put_nowait(("progress", label, t, total))

    return report


def run_variant(job: _Job, progress: Callable[[float, float], None] | None) -> VariantOutcome:
    """Run one variant closed loop; a solver failure or instability becomes an outcome with
    `error` set (the log written so far stays readable)."""
    v = job.variant
    options = RunOptions(
        strategy=v.strategy,
        model=v.model,
        out_dir=job.out_dir,
        log_name=v.log_name,
        qp_backend=job.qp_backend,
        live=job.live,
    )
    log_path = job.out_dir / f"{v.log_name}.mcap"
    try:
        result = run_scenario(job.scenario, job.text, options, progress)
    except (SolverFailure, SimulationError) as exc:
        return VariantOutcome(v, None, None, str(exc), log_path)
    desc = load_robot_description(job.scenario.robot)
    trace = trace_from_run(
        v.label, result.plan, result.record, desc, result.metrics.get("completion_time")
    )
    return VariantOutcome(v, result.metrics, trace, None, result.log_path)


def _run_in_worker(job: _Job) -> VariantOutcome:
    if _worker_queue is not None:
        with contextlib.suppress(Exception):
            _worker_queue.put_nowait(("started", job.variant.label, os.getpid(), 0.0))
    return run_variant(job, _queue_progress(job.variant.label))


def default_jobs() -> int:
    """min(2, usable cores): a comparison has two runs."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    return max(1, min(2, cores))


def run_variants(
    scenario: Scenario,
    text: str,
    variants: Sequence[Variant],
    out_dir: Path,
    *,
    jobs: int | None = None,
    qp_backend: str = "daqp",
    progress: VariantProgress | None = None,
    live: LiveView | None = None,
) -> tuple[VariantOutcome, ...]:
    """Run every variant of `scenario` (its YAML `text` goes into each log) and return the
    outcomes in the order of `variants`. `jobs` (default `default_jobs()`) processes run at
    once; 1 runs everything in this process. Logs go to `out_dir/<variant.log_name>.mcap`.

    Raises ValueError for jobs < 1; a run that breaks is an outcome, not an exception;
    KeyboardInterrupt / SystemExit stop the workers (each closes its log) and propagate,
    as does a signal deferred by `locoplan.interrupt` (checked while waiting for workers).
    With `live`, the variants run one after the other in this process, each served live.
    """
    if jobs is None:
        jobs = default_jobs()
    if jobs < 1:
        raise ValueError(f"jobs must be >= 1, got {jobs}")
    out_dir.mkdir(parents=True, exist_ok=True)
    work = [_Job(scenario, text, v, out_dir, qp_backend, live) for v in variants]
    jobs = 1 if live is not None else min(jobs, len(work))
    if jobs <= 1:
        return tuple(
            run_variant(
                job,
                None if progress is None else _bind_progress(progress, job.variant.label),
            )
            for job in work
        )
    return _run_parallel(work, jobs, progress)


def _bind_progress(progress: VariantProgress, label: str) -> Callable[[float, float], None]:
    def report(t: float, total: float) -> None:
        progress(label, t, total)

    return report


def _drain(q: Any, progress: VariantProgress | None, pids: dict[str, int]) -> None:
    while True:
        try:
            kind, label, a, b = q.get_nowait()
        except (queue.Empty, OSError, ValueError, EOFError):
            return
        if kind == "started":
            pids[label] = int(a)
        elif progress is not None:
            progress(label, float(a), float(b))


def _run_parallel(
    work: list[_Job], jobs: int, progress: VariantProgress | None
) -> tuple[VariantOutcome, ...]:
    ctx = multiprocessing.get_context("spawn")
    q = ctx.Queue()
    pids: dict[str, int] = {}
    results: dict[int, VariantOutcome] = {}
    pool = ProcessPoolExecutor(
        max_workers=jobs, mp_context=ctx, initializer=_init_worker, initargs=(q,)
    )
    try:
        futures: dict[Future[VariantOutcome], int] = {
            pool.submit(_run_in_worker, job): i for i, job in enumerate(work)
        }
        pending = set(futures)
        while pending:
            done, pending = wait(pending, timeout=POLL_PERIOD, return_when=FIRST_COMPLETED)
            interrupt.check()
            _drain(q, progress, pids)
            for f in done:
                results[futures[f]] = f.result()
        _drain(q, progress, pids)
    except BaseException:
        # Interrupted (or a worker raised a bug): stop the runs we started, by their pids, so
        # each closes its MCAP log, then let the error through.
        _drain(q, None, pids)
        for i, job in enumerate(work):
            pid = pids.get(job.variant.label)
            if pid is not None and i not in results:
                with contextlib.suppress(ProcessLookupError, PermissionError):
                    os.kill(pid, signal.SIGINT)
        pool.shutdown(wait=True, cancel_futures=True)
        q.close()
        raise
    pool.shutdown(wait=True)
    q.close()
    return tuple(results[i] for i in range(len(work)))
