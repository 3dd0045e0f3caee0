"""The code that runs inside a worker (a process of the local pool or a Ray task).

Test hooks (for the isolation tests, documented in docs/ci.md): when the environment variable
`LOCOPLAN_TEST_CRASH` equals a job's scenario name (or its job id), the worker running it
dies at once with `os._exit(1)`, as a segfaulting solver would; `LOCOPLAN_TEST_HANG` makes it
sleep until it is stopped (a SIGTERM from the pool's timeout, a SIGINT), as a hung one would.
They are read only here, in the worker.
"""

from __future__ import annotations

import os
import time
import traceback
from collections.abc import Callable
from dataclasses import replace

from locoplan import interrupt
from locoplan.batch.job import Job, Outcome, Status
from locoplan.exceptions import ScenarioError, SimulationError, SolverFailure
from locoplan.plan import PlanError
from locoplan.plan.errors import plan_error_message

CRASH_ENV = "LOCOPLAN_TEST_CRASH"
HANG_ENV = "LOCOPLAN_TEST_HANG"

Progress = Callable[[float, float], None]


def _test_hooks(job: Job) -> None:
    names = {job.name, job.job_id}
    if os.environ.get(CRASH_ENV) in names:
        os._exit(1)
    if os.environ.get(HANG_ENV) in names:
        while True:
            time.sleep(0.05)
            interrupt.check()  # a signal the worker defers (locoplan.interrupt) ends it


def execute_job(job: Job, progress: Progress | None = None) -> Outcome:
    """Run `job` in this process and return how it ended; never raises for a bad script or
    a broken run (those are `error` outcomes). `progress(t, total)` receives simulated time
    (s). KeyboardInterrupt and SystemExit propagate (the MCAP is closed on the way out), as
    does `locoplan.interrupt.Interrupted` for a signal the worker deferred."""
    from locoplan.scenario import load_scenario_file
    from locoplan.sim.run import run_scenario

    start = time.perf_counter()
    _test_hooks(job)

    def ended(status: Status, message: str = "", detail: str = "") -> Outcome:
        wall = time.perf_counter() - start
        return Outcome(job.job_id, status, None, message, detail, wall)

    try:
        loaded = load_scenario_file(job.source, job.text)
    except ScenarioError as exc:
        return ended("error", str(exc.issues[0]), str(exc))
    log_hint = job.options.out_dir / f"{job.options.log_name or loaded.scenario.name}.mcap"
    try:
        result = run_scenario(loaded.scenario, loaded.text, job.options, progress)
    except PlanError as exc:
        where = str(exc) if exc.loc is None else plan_error_message(exc, job.source, job.text)
        return ended("error", f"cannot plan: {where}")
    except (SolverFailure, SimulationError) as exc:
        return ended("error", f"run failed: {exc} (log up to the failure: {log_hint})")
    except Exception as exc:
        # A bug in one run must not take the batch down: report it with its traceback.
        return ended(
            "error", f"internal error: {type(exc).__name__}: {exc}", traceback.format_exc()
        )
    outcome = Outcome(
        job.job_id,
        "passed" if result.passed else "failed",
        result.metrics,
        wall_time=time.perf_counter() - start,
    )
    return outcome if result.passed else replace(outcome, message="; ".join(outcome.failures))
