"""Sweep results: jobs per valid point, CSV rows and text, exit status
(locoplan/batch/sweep_results.py and `sweep_jobs`). No simulation."""

from __future__ import annotations

from pathlib import Path

from locoplan.batch.job import Outcome
from locoplan.batch.sweep import build_points, parse_set, point_label, sweep_jobs
from locoplan.batch.sweep_results import CSV_METRICS, csv_text, sweep_exit_code, sweep_rows

SCRIPT = """version: 1
name: lift
objects:
  box:
    shape: box
    size: [0.2, 0.2, 0.2]
    mass: 4.0   # kg
    position: [0.35, 0.0, 0.55]
fixtures:
  table: {kind: table, position: [0.45, 0.0, 0.0], size: [0.4, 0.6, 0.45]}
tasks:
  - {action: stand, start: 0.0, duration: 0.5}
  - {action: pick, object: box, start: 0.5, duration: 1.0}
end: 2.0
"""


def test_jobs_rows_and_csv(tmp_path: Path) -> None:
    axes = [parse_set("objects.box.mass=-1,2,3")]
    points = build_points(tmp_path / "lift.yaml", SCRIPT, axes)
    jobs = sweep_jobs(points, axes, "lift", tmp_path / "lift.yaml", tmp_path / "out")
    assert [j.job_id for j in jobs] == ["objects.box.mass=2", "objects.box.mass=3"]
    assert [j.options.log_name for j in jobs] == ["lift-0001", "lift-0002"]
    assert all(j.options.out_dir == tmp_path / "out" for j in jobs)
    metrics = {
        "fell": False, "completed": True, "completion_time": 1.5, "peak_torque_ratio": 0.4321,
        "yaw_difference_deg": None, "passed": True, "real_time_factor": 1.7,
    }  # fmt: skip
    outcomes = {
        point_label(axes, (2,)): Outcome("objects.box.mass=2", "passed", metrics),
        point_label(axes, (3,)): Outcome("objects.box.mass=3", "error", message="run failed"),
    }
    rows = sweep_rows(axes, points, outcomes)
    assert list(rows[0]) == ["objects.box.mass", *CSV_METRICS]
    text = csv_text(axes, rows)
    lines = text.splitlines()
    assert lines[0] == "objects.box.mass," + ",".join(CSV_METRICS)
    assert lines[1].startswith('-1,,,,,,,,"objects.box.mass=-1: invalid: ')
    assert lines[2] == "2,false,true,1.5,0.4321,,true,1.7,"
    assert lines[3] == "3,,,,,,,,run failed"
    assert sweep_exit_code(points, outcomes) == 1


def test_all_passed_exits_0(tmp_path: Path) -> None:
    axes = [parse_set("objects.box.mass=2")]
    points = build_points(tmp_path / "lift.yaml", SCRIPT, axes)
    outcomes = {"objects.box.mass=2": Outcome("objects.box.mass=2", "passed", {"passed": True})}
    assert sweep_exit_code(points, outcomes) == 0
