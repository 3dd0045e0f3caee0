"""Running a sweep's points and writing its results: one CSV row per point.

The CSV has one row per point, sorted by the set values (`locoplan.batch.sweep`): the values,
then `CSV_METRICS`; floats are written with `repr` after the metrics' own rounding, so the same
points give the same bytes on every backend (except the wall-time columns,
`WALL_TIME_COLUMNS`).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Mapping, Sequence
from typing import Any

from locoplan.batch.job import Job, Outcome, RunListener
from locoplan.batch.sweep import SweepAxis, SweepPoint, format_value, point_label

# Metric columns of the CSV, in order (cli-contract.md names); `error` says why a point has
# no metrics (invalid, broken run, crashed or timed-out worker).
CSV_METRICS = (
    "fell",
    "completed",
    "completion_time",
    "peak_torque_ratio",
    "yaw_difference_deg",
    "passed",
    "real_time_factor",
    "error",
)
# Columns that depend on the machine's speed, not the simulation: they differ between runs.
WALL_TIME_COLUMNS = ("real_time_factor",)
# Columns `--metric` may plot (numbers, or booleans drawn as 0/1).
PLOTTABLE = tuple(c for c in CSV_METRICS if c != "error")
BACKENDS = ("local", "ray")


def sweep_rows(
    axes: Sequence[SweepAxis],
    points: Sequence[SweepPoint],
    outcomes: Mapping[str, Outcome],
) -> list[dict[str, Any]]:
    """One row per point in sorted order: the set values (by key) then `CSV_METRICS`.
    `outcomes` maps job ids (`point_label`) to outcomes; an invalid point has no outcome."""
    rows = []
    for point in points:
        row: dict[str, Any] = {a.key: v for a, v in zip(axes, point.values, strict=True)}
        outcome = outcomes.get(point_label(axes, point.values))
        metrics: Mapping[str, Any] = {}
        error = point.error or ""
        if outcome is not None:
            metrics = outcome.metrics or {}
            if outcome.status in ("error", "skipped"):
                error = outcome.message
        for column in CSV_METRICS:
            row[column] = error if column == "error" else metrics.get(column)
        rows.append(row)
    return rows


def csv_text(axes: Sequence[SweepAxis], rows: Sequence[Mapping[str, Any]]) -> str:
    """The CSV (header, then one line per row, `\\n` line ends)."""
    stream = io.StringIO()
    writer = csv.writer(stream, lineterminator="\n")
    columns = [a.key for a in axes] + list(CSV_METRICS)
    writer.writerow(columns)
    for row in rows:
        writer.writerow([format_value(row.get(c)) for c in columns])
    return stream.getvalue()


def sweep_exit_code(points: Sequence[SweepPoint], outcomes: Mapping[str, Outcome]) -> int:
    """0 when every point is valid and passed, 1 otherwise (some failed, errored or were
    invalid). Exit 2 (no valid point) is the CLI's call."""
    if any(p.error is not None for p in points):
        return 1
    return 0 if all(o.status == "passed" for o in outcomes.values()) else 1


def run_sweep(
    jobs: Sequence[Job],
    backend: str = "local",
    workers: int | None = None,
    address: str | None = None,
    timeout: float | None = None,
    listener: RunListener | None = None,
) -> dict[str, Outcome]:
    """Run the sweep's jobs on `backend` ("local": worker processes; "ray": Ray tasks, on the
    cluster at `address` or a local Ray), write each run's metrics JSON beside its MCAP, and
    return the outcomes by job id. Raises BackendUnavailable when Ray is missing or cannot
    start, ValueError for an unknown backend."""
    from locoplan.batch.batch import write_metrics
    from locoplan.batch.pool import run_local

    if backend == "local":
        outcomes = run_local(jobs, workers, timeout, listener)
    elif backend == "ray":
        from locoplan.batch.ray_backend import run_ray, workers_for

        n = workers_for(len(jobs), workers, address)
        outcomes = run_ray(jobs, n, address, timeout, listener)
    else:
        raise ValueError(f"unknown backend '{backend}'; allowed: {', '.join(BACKENDS)}")
    by_id = {job.job_id: job for job in jobs}
    for outcome in outcomes:
        write_metrics(by_id[outcome.job_id], outcome)
    return {outcome.job_id: outcome for outcome in outcomes}
