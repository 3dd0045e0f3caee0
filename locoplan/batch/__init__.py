"""Many runs at once: CI batches of task scripts and parameter sweeps.

`prepare_batch(paths, out_dir)` finds and validates scripts; `run_batch(cases, workers, ...)`
runs the valid ones in isolated worker processes (`pool.run_local`), served from a content
cache when unchanged; `write_junit` reports them. `parse_set` / `build_points` /
`sweep_jobs` / `sweep_rows` / `csv_text` make a sweep, run on `run_local` or on Ray
(`ray_backend.run_ray`, optional). Nothing here prints; `locoplan.cli` draws the progress
from a `RunListener`.
"""

from locoplan.batch.batch import (
    BatchCase,
    BatchResult,
    batch_exit_code,
    metrics_path,
    prepare_batch,
    run_batch,
    write_metrics,
)
from locoplan.batch.cache import CACHE_DIRNAME, ResultCache, cache_key, code_fingerprint
from locoplan.batch.discovery import SCRIPT_SUFFIXES, discover_scripts
from locoplan.batch.errors import BackendUnavailable, BatchInputError, SweepSpecError
from locoplan.batch.job import STATUSES, Job, Outcome, RunListener, Status, failed_expectations
from locoplan.batch.junit import junit_xml, write_junit
from locoplan.batch.pool import default_workers, run_local
from locoplan.batch.sweep import (
    SweepAxis,
    SweepPoint,
    build_points,
    format_value,
    parse_set,
    point_label,
    sweep_jobs,
)
from locoplan.batch.sweep_results import (
    BACKENDS,
    CSV_METRICS,
    PLOTTABLE,
    WALL_TIME_COLUMNS,
    csv_text,
    run_sweep,
    sweep_exit_code,
    sweep_rows,
)

__all__ = [
    "BACKENDS",
    "CACHE_DIRNAME",
    "CSV_METRICS",
    "PLOTTABLE",
    "SCRIPT_SUFFIXES",
    "STATUSES",
    "WALL_TIME_COLUMNS",
    "BackendUnavailable",
    "BatchCase",
    "BatchInputError",
    "BatchResult",
    "Job",
    "Outcome",
    "ResultCache",
    "RunListener",
    "Status",
    "SweepAxis",
    "SweepPoint",
    "SweepSpecError",
    "batch_exit_code",
    "build_points",
    "cache_key",
    "code_fingerprint",
    "csv_text",
    "default_workers",
    "discover_scripts",
    "failed_expectations",
    "format_value",
    "junit_xml",
    "metrics_path",
    "parse_set",
    "point_label",
    "prepare_batch",
    "run_batch",
    "run_local",
    "run_sweep",
    "sweep_exit_code",
    "sweep_jobs",
    "sweep_rows",
    "write_junit",
    "write_metrics",
]
