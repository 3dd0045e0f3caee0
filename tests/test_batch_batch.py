"""Preparing and running a batch (locoplan/batch/batch.py) without simulating: discovery and
validation, output layout, JUnit class names, cache hits and --fail-fast leftovers."""

from __future__ import annotations

from pathlib import Path

from locoplan.batch.batch import batch_exit_code, metrics_path, prepare_batch, run_batch
from locoplan.batch.cache import ResultCache
from locoplan.batch.job import Job, Outcome

STAND = """version: 1
name: {name}
tasks:
  - {{action: stand, start: 0.0, duration: 0.5}}
end: 0.5
"""
BAD = "version: 1\nname: bad\ntasks:\n  - {action: jump, start: 0.0, duration: 1.0}\n"


class _Recorder:
    def __init__(self) -> None:
        self.ended: list[Outcome] = []

    def started(self, job: Job) -> None:
        raise AssertionError(f"nothing should run, {job.job_id} started")

    def progress(self, job: Job, t: float, total: float) -> None:
        raise AssertionError("nothing should run")

    def finished(self, outcome: Outcome) -> None:
        self.ended.append(outcome)


def _suite(tmp_path: Path) -> Path:
    root = tmp_path / "suite"
    (root / "sub").mkdir(parents=True)
    (root / "a.yaml").write_text(STAND.format(name="a"))
    (root / "sub" / "b.yml").write_text(STAND.format(name="b"))
    (root / "bad.yaml").write_text(BAD)
    return root


def test_prepare_validates_and_lays_out_outputs(tmp_path: Path) -> None:
    root = _suite(tmp_path)
    out = tmp_path / "out"
    cases = prepare_batch([root], out)
    assert [c.path.relative_to(root).as_posix() for c in cases] == [
        "a.yaml",
        "bad.yaml",
        "sub/b.yml",
    ]
    a, bad, b = cases
    assert (a.classname, b.classname, bad.classname) == ("suite", "suite.sub", "suite")
    assert bad.job is None and bad.invalid is not None
    assert bad.invalid.status == "error"
    assert bad.invalid.message.startswith(f"{root / 'bad.yaml'}:4:14: unknown action 'jump'")
    assert a.job is not None and b.job is not None
    assert (a.job.options.out_dir, a.job.options.log_name) == (out, "a")
    assert (b.job.options.out_dir, b.job.options.log_name) == (out / "sub", "b")
    assert metrics_path(b.job) == out / "sub" / "b.json"
    assert a.cache_key is not None and a.cache_key != b.cache_key
    assert all(c.cache_key is None for c in prepare_batch([root], out, use_cache=False))


def test_cached_cases_are_served_without_running(tmp_path: Path) -> None:
    root = tmp_path / "one"
    root.mkdir()
    (root / "a.yaml").write_text(STAND.format(name="a"))
    out = tmp_path / "out"
    (case,) = prepare_batch([root], out)
    assert case.job is not None and case.cache_key is not None
    log = out / "a.mcap"
    log.parent.mkdir(parents=True)
    log.write_bytes(b"")
    metrics = {"scenario": "a", "log": str(log), "expectations": {}, "passed": True}
    ResultCache(out / ".cache").put(case.cache_key, Outcome("a", "passed", metrics))
    recorder = _Recorder()
    (result,) = run_batch([case], cache_dir=out / ".cache", listener=recorder)
    assert result.outcome.cached and result.outcome.status == "passed"
    assert result.outcome.job_id == case.case_id
    assert recorder.ended == [result.outcome]
    assert batch_exit_code([result]) == 0


def test_fail_fast_after_an_invalid_script_runs_nothing(tmp_path: Path) -> None:
    root = _suite(tmp_path)
    cases = prepare_batch([root], tmp_path / "out", use_cache=False)
    recorder = _Recorder()
    results = run_batch(cases, listener=recorder, fail_fast=True)
    assert [r.outcome.status for r in results] == ["skipped", "error", "skipped"]
    assert results[0].outcome.message == "not run (--fail-fast)"
    assert len(recorder.ended) == 3
    assert batch_exit_code(results) == 1
    assert not (tmp_path / "out").exists()
