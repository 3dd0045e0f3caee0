"""Batch and sweep summary tables (locoplan/report/batch_table.py)."""

from __future__ import annotations

from pathlib import Path

from rich.console import Console

from locoplan.batch.batch import BatchCase, BatchResult
from locoplan.batch.job import Job, Outcome
from locoplan.batch.sweep import parse_set
from locoplan.report.batch_table import batch_counts, batch_table, sweep_table
from locoplan.sim.run import RunOptions


def _render(table: object) -> str:
    console = Console(width=200, record=True, color_system=None)
    console.print(table)
    return console.export_text()


def _result(path: str, outcome: Outcome) -> BatchResult:
    job = Job(path, "x", path, "", RunOptions())
    return BatchResult(BatchCase(path, Path(path), "s", job, None), outcome)


def test_batch_table_rows_and_caption() -> None:
    failed = {
        "completion_time": 4.9,
        "peak_torque_ratio": 1.234,
        "fell": True,
        "fall_time": 3.0,
        "expectations": {"no_fall": {"ok": False, "value": True, "limit": True}},
    }
    results = [
        _result("a.yaml", Outcome("a.yaml", "passed", {"peak_torque_ratio": 0.5}, wall_time=3.21)),
        _result("b.yaml", Outcome("b.yaml", "failed", failed, cached=True)),
        _result("c.yaml", Outcome("c.yaml", "error", message="worker died (exit status 1)")),
    ]
    text = _render(batch_table(results))
    lines = {line.split()[1]: line for line in text.splitlines() if ".yaml" in line}
    assert "passed" in lines["a.yaml"] and "3.2 s" in lines["a.yaml"] and "0.50" in lines["a.yaml"]
    assert "failed (cached)" in lines["b.yaml"] and "no_fall: fell at t=3.00 s" in lines["b.yaml"]
    assert "4.90 s" in lines["b.yaml"] and "yes" in lines["b.yaml"]
    assert "worker died (exit status 1)" in lines["c.yaml"]
    assert "1 passed, 1 failed, 1 error (1 from the cache)" in text
    assert batch_counts(results) == {"passed": 1, "failed": 1, "error": 1, "skipped": 0}


def test_sweep_table_shows_values_metric_and_errors() -> None:
    axes = [parse_set("objects.box.mass=1,2")]
    rows = [
        {"objects.box.mass": 1, "peak_torque_ratio": 0.25, "fell": False, "passed": True},
        {"objects.box.mass": 2, "peak_torque_ratio": None, "fell": None, "error": "boom"},
    ]
    text = _render(sweep_table(axes, rows, "peak_torque_ratio"))
    assert "objects.box.mass" in text and "0.25" in text and "boom" in text
