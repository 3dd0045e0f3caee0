"""What a worker does with one job (locoplan/batch/worker.py), run in this process."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from locoplan.batch.job import Job
from locoplan.batch.worker import execute_job
from locoplan.sim.run import RunOptions

SHORT = """version: 1
name: half-second
tasks:
  - {action: stand, start: 0.0, duration: 0.5}
end: 0.5
expect:
  no_fall: true
  max_torque_ratio: 0.001
"""


def test_invalid_script_is_an_error_with_its_position(tmp_path: Path) -> None:
    text = SHORT.replace("stand", "jump")
    job = Job("x", "half-second", str(tmp_path / "x.yaml"), text, RunOptions(out_dir=tmp_path))
    outcome = execute_job(job)
    assert outcome.status == "error" and outcome.metrics is None
    assert outcome.message.startswith(f"{tmp_path / 'x.yaml'}:4:14: unknown action 'jump'")
    assert not list(tmp_path.iterdir())  # nothing simulated, no log


@pytest.mark.closed_loop
def test_a_run_returns_its_metrics_and_failed_expectations(tmp_path: Path) -> None:
    options = RunOptions(out_dir=tmp_path, log_name="h")
    job = Job("x", "half-second", str(tmp_path / "x.yaml"), SHORT, options)
    ticks: list[float] = []
    outcome = execute_job(job, lambda t, total: ticks.append(t))
    assert outcome.status == "failed"
    assert outcome.metrics is not None and outcome.metrics["log"] == str(tmp_path / "h.mcap")
    assert (tmp_path / "h.mcap").stat().st_size > 0
    assert outcome.message.startswith("max_torque_ratio: peak torque ratio ")
    assert outcome.failures == (outcome.message,)
    assert ticks and ticks[-1] <= 0.5
    assert outcome.wall_time > 0
    json.dumps(dict(outcome.metrics))  # crosses process boundaries as plain data
