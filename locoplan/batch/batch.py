"""A batch: find task scripts, validate them all, run the valid ones in parallel.

`prepare_batch` finds and validates (no simulation); `run_batch` serves unchanged runs from
the cache, runs the rest on the local worker pool, writes each run's metrics JSON beside its
MCAP log, and returns one `BatchResult` per script in path order. Nothing here prints.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from locoplan.batch.cache import ResultCache, cache_key, code_fingerprint, robot_fingerprint
from locoplan.batch.discovery import common_root, discover_scripts
from locoplan.batch.job import Job, Outcome, RunListener
from locoplan.batch.pool import run_local
from locoplan.exceptions import ScenarioError
from locoplan.sim.run import RunOptions


@dataclass(frozen=True, slots=True)
class BatchCase:
    """One script found by a batch.

    `case_id` is the path as found (relative when the command line was); `classname` the
    dotted folder (JUnit), relative to the parent of the folder holding all scripts, so
    `locoplan batch scenarios/` gives `scenarios` and `scenarios.sub`; `job` is None for an
    invalid script, whose `invalid` outcome holds the issues (`path:line:col: message`).
    """

    case_id: str
    path: Path
    classname: str
    job: Job | None
    invalid: Outcome | None
    cache_key: str | None = None


@dataclass(frozen=True, slots=True)
class BatchResult:
    """A case and how it ended."""

    case: BatchCase
    outcome: Outcome


def _classname(folder: Path) -> str:
    parts = [part.replace(".", "_") for part in folder.parts if part not in ("", "/")]
    return ".".join(parts) or "scripts"


def prepare_batch(
    paths: Sequence[str | Path],
    out_dir: Path,
    options: RunOptions | None = None,
    use_cache: bool = True,
    max_sim_time: float | None = None,
) -> list[BatchCase]:
    """Find the scripts under `paths` and validate each (no simulation).

    Each valid script becomes a job whose MCAP goes to `out_dir`, mirroring the scripts'
    folders below the folder holding them all (`out_dir/<sub>/<stem>.mcap`). With
    `max_sim_time` (s), a script asking for more simulated time is invalid
    (`locoplan.scenario.limits`). Raises BatchInputError when a path does not exist or no
    script is found.
    """
    from locoplan.scenario import load_scenario_file
    from locoplan.scenario.limits import sim_time_issue

    options = options or RunOptions()
    files = discover_scripts(paths)
    root = common_root(files)
    code = code_fingerprint() if use_cache else ""
    cases: list[BatchCase] = []
    used_logs: set[Path] = set()
    for path in files:
        case_id = path.as_posix()
        rel_folder = path.resolve().parent.relative_to(root)
        classname = _classname(Path(root.name) / rel_folder)
        try:
            loaded = load_scenario_file(path)
        except ScenarioError as exc:
            invalid = Outcome(case_id, "error", message=str(exc.issues[0]), detail=str(exc))
            cases.append(BatchCase(case_id, path, classname, None, invalid))
            continue
        too_long = None if max_sim_time is None else sim_time_issue(loaded, max_sim_time)
        if too_long is not None:
            invalid = Outcome(case_id, "error", message=str(too_long), detail=str(too_long))
            cases.append(BatchCase(case_id, path, classname, None, invalid))
            continue
        run_dir = out_dir / rel_folder
        log_name = path.stem
        if run_dir / log_name in used_logs:  # a.yaml and a.yml side by side
            log_name = path.name.replace(".", "-")
        used_logs.add(run_dir / log_name)
        job = Job(
            case_id,
            loaded.scenario.name,
            str(path),
            loaded.text,
            replace(options, out_dir=run_dir, log_name=log_name, log=True),
        )
        key = cache_key(job, code, robot_fingerprint(loaded.robot_path)) if use_cache else None
        cases.append(BatchCase(case_id, path, classname, job, None, key))
    return cases


def metrics_path(job: Job) -> Path:
    """Where a job's metrics JSON goes: beside its MCAP, `<log_name>.json`."""
    return job.options.out_dir / f"{job.options.log_name or job.name}.json"


def write_metrics(job: Job, outcome: Outcome) -> None:
    """Write the outcome's metrics (if any) to `metrics_path(job)`, atomically."""
    if outcome.metrics is None:
        return
    path = metrics_path(job)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(f".{os.getpid()}.tmp")
    tmp.write_text(json.dumps(dict(outcome.metrics), indent=2) + "\n", "utf-8")
    os.replace(tmp, path)


class _Forward:
    """Writes metrics and cache entries as runs end, then tells the caller's listener."""

    def __init__(self, by_id: dict[str, BatchCase], cache: ResultCache | None,
                 listener: RunListener | None) -> None:  # fmt: skip
        self.by_id = by_id
        self.cache = cache
        self.listener = listener

    def started(self, job: Job) -> None:
        if self.listener is not None:
            self.listener.started(job)

    def progress(self, job: Job, t: float, total: float) -> None:
        if self.listener is not None:
            self.listener.progress(job, t, total)

    def finished(self, outcome: Outcome) -> None:
        case = self.by_id[outcome.job_id]
        if case.job is not None and outcome.metrics is not None and not outcome.cached:
            write_metrics(case.job, outcome)
            if self.cache is not None and case.cache_key is not None:
                self.cache.put(case.cache_key, outcome)
        if self.listener is not None:
            self.listener.finished(outcome)


def run_batch(
    cases: Sequence[BatchCase],
    workers: int | None = None,
    timeout: float | None = None,
    cache_dir: Path | None = None,
    listener: RunListener | None = None,
    fail_fast: bool = False,
    backend: str = "local",
    address: str | None = None,
) -> list[BatchResult]:
    """Run the valid cases (at most `workers` at a time, each bounded by `timeout` seconds)
    and return every case's result in the order of `cases`.

    `backend` "local" runs them in worker processes here (`pool.run_local`), "ray" as Ray
    tasks (`ray_backend.run_ray`) on the cluster at `address`, or on a local Ray started for
    the call when `address` is None; validation, the cache, the metrics JSON and the results
    are the same on both. Raises BackendUnavailable when Ray is missing or unreachable,
    ValueError for an unknown backend.

    Invalid cases are `error` results without running. With `cache_dir`, a case whose cache
    key has a stored outcome is served from it (`cached=True`, its log left as it was) and
    new outcomes are stored. With `fail_fast`, the first case that fails or errs (an invalid
    script included) stops the rest, reported as `skipped`. The listener hears of invalid and
    cached cases as finished, before any run starts.
    """
    cache = ResultCache(cache_dir) if cache_dir is not None else None
    by_id = {case.case_id: case for case in cases}
    forward = _Forward(by_id, cache, listener)
    outcomes: dict[str, Outcome] = {}
    to_run: list[Job] = []
    for case in cases:
        if case.invalid is not None:
            outcomes[case.case_id] = case.invalid
            forward.finished(case.invalid)
            continue
        assert case.job is not None  # a valid case has a job
        hit = None
        if cache is not None and case.cache_key is not None:
            hit = cache.get(case.cache_key, case.case_id)
        if hit is not None:
            outcomes[case.case_id] = hit
            forward.finished(hit)
        else:
            to_run.append(case.job)
    broken = any(o.status in ("failed", "error") for o in outcomes.values())
    if fail_fast and broken:
        for job in to_run:
            skipped = Outcome(job.job_id, "skipped", message="not run (--fail-fast)")
            outcomes[job.job_id] = skipped
            forward.finished(skipped)
    elif to_run:
        for outcome in _run_jobs(to_run, backend, workers, address, timeout, forward, fail_fast):
            outcomes[outcome.job_id] = outcome
    return [BatchResult(case, outcomes[case.case_id]) for case in cases]


def _run_jobs(
    jobs: Sequence[Job],
    backend: str,
    workers: int | None,
    address: str | None,
    timeout: float | None,
    listener: RunListener,
    fail_fast: bool,
) -> list[Outcome]:
    if backend == "local":
        return run_local(jobs, workers, timeout, listener, fail_fast)
    if backend == "ray":
        from locoplan.batch.ray_backend import run_ray, workers_for

        n = workers_for(len(jobs), workers, address)
        return run_ray(jobs, n, address, timeout, listener, fail_fast)
    raise ValueError(f"unknown backend '{backend}'; allowed: local, ray")


def batch_exit_code(results: Sequence[BatchResult]) -> int:
    """0 when every case passed, 1 otherwise (cli-contract.md)."""
    return 0 if all(r.outcome.status == "passed" for r in results) else 1
