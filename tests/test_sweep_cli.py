"""`locoplan sweep` end to end in a subprocess: the CSV and plot, invalid points, exit codes,
and the Ray backend giving the same CSV as the local one (issue 7)."""

from __future__ import annotations

import csv
import io
import os
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from locoplan.batch.sweep_results import CSV_METRICS, WALL_TIME_COLUMNS
from locoplan.cli import app

LOCOPLAN = [sys.executable, "-m", "locoplan.cli"]

# 0.5 s standing with a 2 kg box on a table: two valid points of about 1 s simulated time
# each (the duration and `end` are swept together), one invalid (negative duration).
SCRIPT = """version: 1
name: sweepme
objects:
  box: {shape: box, size: [0.2, 0.2, 0.2], mass: 2.0, position: [0.5, 0.0, 0.55]}
fixtures:
  table: {kind: table, position: [0.6, 0.0, 0.0], size: [0.4, 0.6, 0.45]}
tasks:
  - {action: stand, start: 0.0, duration: 1.0}
end: 1.0
expect:
  no_fall: true
  max_torque_ratio: 1.0
"""
SETS = ["--set", "tasks.0.duration=0.6,1.0,-1", "--set", "end=1.0"]


def _sweep(args: list[str], env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*LOCOPLAN, "sweep", *args],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
        env={**os.environ, **(env or {})},
    )


def _rows(path: Path) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(path.read_text())))


def _without_wall_time(path: Path) -> list[dict[str, str]]:
    return [{k: v for k, v in r.items() if k not in WALL_TIME_COLUMNS} for r in _rows(path)]


@pytest.fixture(scope="module")
def local_sweep(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    root = tmp_path_factory.mktemp("sweep")
    script = root / "sweepme.yaml"
    script.write_text(SCRIPT)
    out = root / "local"
    res = _sweep([str(script), *SETS, "--out", str(out), "--jobs", "2"])
    assert res.returncode == 1, res.stderr  # the invalid point makes it 1
    assert "Traceback" not in res.stdout + res.stderr
    assert "invalid point tasks.0.duration=-1,end=1.0: invalid: " in res.stderr
    return script, out


@pytest.mark.closed_loop
def test_csv_and_plot_have_one_row_per_point(local_sweep: tuple[Path, Path]) -> None:
    script, out = local_sweep
    csv_path = out / "sweepme-sweep.csv"
    rows = _rows(csv_path)
    assert list(rows[0]) == ["tasks.0.duration", "end", *CSV_METRICS]
    assert [(r["tasks.0.duration"], r["end"]) for r in rows] == [
        ("-1", "1.0"), ("0.6", "1.0"), ("1.0", "1.0"),
    ]  # fmt: skip
    invalid, short, full = rows
    # The invalid point names its key, value and the line:column of the value it set.
    assert invalid["error"].startswith(f"tasks.0.duration=-1,end=1.0: invalid: {script}:8:43: ")
    assert invalid["fell"] == "" and invalid["peak_torque_ratio"] == ""
    for row in (short, full):
        assert row["error"] == "" and row["fell"] == "false" and row["passed"] == "true"
        assert 0.0 < float(row["peak_torque_ratio"]) < 1.0
        assert float(row["real_time_factor"]) > 0.0
    assert float(short["completion_time"]) <= 0.7  # the stand ends at 0.6 s
    assert (out / "sweepme-sweep.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "sweepme-0001.mcap").is_file() and (out / "sweepme-0001.json").is_file()
    assert not (out / "sweepme-0000.mcap").exists()  # the invalid point did not run


@pytest.mark.closed_loop
def test_ray_backend_gives_the_same_csv(local_sweep: tuple[Path, Path], tmp_path: Path) -> None:
    pytest.importorskip("ray", reason="Ray is not installed (pip install 'locoplan[ray]')")
    script, out = local_sweep
    ray_out = tmp_path / "ray"
    # --out differs, so the logs do too; the CSV holds no path for valid points.
    res = _sweep([str(script), *SETS, "--out", str(ray_out), "--backend", "ray", "--jobs", "2"])
    assert res.returncode == 1, res.stderr
    assert "Traceback" not in res.stdout + res.stderr
    local_rows = _without_wall_time(out / "sweepme-sweep.csv")
    ray_rows = _without_wall_time(ray_out / "sweepme-sweep.csv")
    assert ray_rows == local_rows
    assert (ray_out / "sweepme-0002.mcap").is_file()


def test_missing_ray_says_how_to_install(tmp_path: Path) -> None:
    # A `ray` module that fails to import, as when the package is absent.
    (tmp_path / "ray.py").write_text("raise ImportError('No module named ray')\n")
    script = tmp_path / "s.yaml"
    script.write_text(SCRIPT)
    res = _sweep(
        [str(script), "--set", "end=1.0", "--backend", "ray"], env={"PYTHONPATH": str(tmp_path)}
    )
    assert res.returncode == 2
    assert "pip install 'locoplan[ray]'" in res.stderr
    assert "Traceback" not in res.stderr


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--set", "end"], "--set end: expected KEY=VALUES"),
        (["--set", "tasks.3.start=1"], "tasks.3: index out of range"),
        (["--set", "end=1", "--metric", "mass"], "unknown --metric 'mass'"),
        (["--set", "end=1", "--backend", "dask"], "unknown --backend 'dask'"),
        (["--set", "end=1", "--address", "auto"], "--address needs --backend ray"),
        (["--set", "tasks.0.duration=-1,-2"], "no valid point among 2"),
    ],
)
def test_bad_command_lines_exit_2(tmp_path: Path, args: list[str], message: str) -> None:
    # In process (nothing is simulated): the same command code, without interpreter start-up.
    script = tmp_path / "s.yaml"
    script.write_text(SCRIPT)
    res = CliRunner().invoke(app, ["sweep", str(script), *args, "--out", str(tmp_path / "o")])
    assert res.exit_code == 2, res.output
    assert message in res.stderr
    assert res.exception is None or isinstance(res.exception, SystemExit)
