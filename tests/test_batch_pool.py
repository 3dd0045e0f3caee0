"""The local worker pool (locoplan/batch/pool.py): jobs in their own processes, outcomes in
order, --fail-fast. Crashes and timeouts are injected through the CLI in test_batch_cli.py
(the test hooks are environment variables, read by the worker at its start)."""

from __future__ import annotations

from pathlib import Path

import pytest

from locoplan.batch.job import Job, Outcome
from locoplan.batch.pool import default_workers, run_local
from locoplan.sim.run import RunOptions

BAD = "version: 1\nname: {name}\ntasks:\n  - {{action: jump, start: 0.0, duration: 1.0}}\n"


def _bad_job(tmp_path: Path, name: str) -> Job:
    return Job(name, name, str(tmp_path / f"{name}.yaml"), BAD.format(name=name), RunOptions())


class _Recorder:
    def __init__(self) -> None:
        self.events: list[tuple[str, str]] = []

    def started(self, job: Job) -> None:
        self.events.append(("started", job.job_id))

    def progress(self, job: Job, t: float, total: float) -> None:
        self.events.append(("progress", job.job_id))

    def finished(self, outcome: Outcome) -> None:
        self.events.append((outcome.status, outcome.job_id))


def test_outcomes_come_back_in_job_order_from_worker_processes(tmp_path: Path) -> None:
    jobs = [_bad_job(tmp_path, n) for n in ("c", "a", "b")]
    recorder = _Recorder()
    outcomes = run_local(jobs, workers=2, listener=recorder)
    assert [o.job_id for o in outcomes] == ["c", "a", "b"]
    # The worker re-validates the script: a bad one is an error naming its line, not a crash.
    assert all(
        o.status == "error" and ":4:14: unknown action 'jump'" in o.message for o in outcomes
    )
    assert sorted(e for e in recorder.events if e[0] == "started") == [
        ("started", "a"), ("started", "b"), ("started", "c"),
    ]  # fmt: skip


def test_fail_fast_skips_what_is_left(tmp_path: Path) -> None:
    jobs = [_bad_job(tmp_path, n) for n in ("a", "b", "c")]
    outcomes = run_local(jobs, workers=1, fail_fast=True)
    assert [o.status for o in outcomes] == ["error", "skipped", "skipped"]
    assert outcomes[1].message == "not run (--fail-fast)"


def test_arguments_are_checked(tmp_path: Path) -> None:
    job = _bad_job(tmp_path, "a")
    with pytest.raises(ValueError, match="workers"):
        run_local([job], workers=0)
    with pytest.raises(ValueError, match="timeout"):
        run_local([job], timeout=0)
    with pytest.raises(ValueError, match="unique"):
        run_local([job, job])
    assert default_workers() >= 1
