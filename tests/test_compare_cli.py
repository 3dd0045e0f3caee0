"""`locoplan compare` end to end in a subprocess: exit codes, compare.json, one MCAP per run,
the plots, and what it says when both strategies schedule the same (cli-contract.md)."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from compare_fixtures import SHORT_STAND, SHORT_TURN

from locoplan.log.reader import read_log
from locoplan.report.compare_plots import FILE_NAMES, png_size

LOCOPLAN = [sys.executable, "-m", "locoplan.cli"]


def _run(args: list[str], stdin: str | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*LOCOPLAN, *args], input=stdin, capture_output=True, text=True, timeout=300, check=False
    )


def _write(tmp_path: Path, text: str, name: str = "task.yaml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.closed_loop
def test_compare_strategies_writes_everything(tmp_path: Path) -> None:
    out = tmp_path / "out"
    res = _run(["compare", str(_write(tmp_path, SHORT_TURN)), "--out", str(out)])
    assert res.returncode == 0, res.stderr
    data = json.loads((out / "compare.json").read_text())
    assert list(data) == ["quasi-static", "dynamic"]
    for label in data:
        assert data[label]["strategy"] == label
        log = read_log(out / f"short-turn-{label}.mcap")
        assert log.complete and log.metrics is not None
        assert log.metrics["strategy"] == label
    for name in FILE_NAMES.values():
        w, h = png_size(out / name)
        assert w >= 500 and h >= 500  # readable at 100 dpi
    assert "schedules identical:" in res.stdout
    assert "agree within one MPC step" in res.stdout
    assert "Δ = dynamic − quasi-static" in res.stdout
    assert "Traceback" not in res.stderr


@pytest.mark.closed_loop
def test_compare_models_from_stdin_failed_expectation_exits_1(tmp_path: Path) -> None:
    text = SHORT_STAND.replace("max_torque_ratio: 1.0", "max_torque_ratio: 0.01")
    out = tmp_path / "m"
    res = _run(["compare", "-", "--models", "--out", str(out), "--no-plots", "--quiet"], text)
    assert res.returncode == 1, res.stderr
    data = json.loads((out / "compare.json").read_text())
    assert list(data) == ["external-force", "combined"]
    assert {data[k]["model"] for k in data} == {"external-force", "combined"}
    assert not data["combined"]["expectations"]["max_torque_ratio"]["ok"]
    assert sorted(p.name for p in out.iterdir()) == [
        "compare.json",
        "short-stand-combined.mcap",
        "short-stand-external-force.mcap",
    ]
    assert res.stdout == ""  # --quiet
    assert "Traceback" not in res.stderr


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--strategy", "dynamic"], "--strategy applies with --models only"),
        (["--models", "--strategy", "fast"], "unknown --strategy 'fast'"),
        (["--jobs", "0"], "--jobs must be at least 1"),
        (["--qp", "osqp"], "unknown --qp 'osqp'"),
    ],
)
def test_bad_options_exit_2(tmp_path: Path, args: list[str], message: str) -> None:
    res = _run(["compare", str(_write(tmp_path, SHORT_STAND)), "--out", str(tmp_path), *args])
    assert res.returncode == 2
    assert message in res.stderr
    assert not (tmp_path / "compare.json").exists()


def test_bad_script_exits_2_with_position(tmp_path: Path) -> None:
    script = _write(tmp_path, SHORT_STAND.replace("action: stand", "action: jump"))
    res = _run(["compare", str(script), "--out", str(tmp_path / "o")])
    assert res.returncode == 2
    assert f"{script}:4:" in res.stderr
    assert "Traceback" not in res.stderr
    assert not (tmp_path / "o").exists()


def test_help_names_outputs_and_exit_codes() -> None:
    res = _run(["compare", "--help"])
    assert res.returncode == 0
    for word in ("--models", "--jobs", "--strategy", "compare.json", "yaw.png", "Exit status"):
        assert word in res.stdout


@pytest.mark.closed_loop
def test_ctrl_c_stops_both_runs_and_closes_their_logs(tmp_path: Path) -> None:
    out = tmp_path / "out"
    script = Path(__file__).resolve().parent.parent / "scenarios" / "walk-square.yaml"
    proc = subprocess.Popen(
        [*LOCOPLAN, "compare", str(script), "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    logs = [out / f"walk-square-{label}.mcap" for label in ("quasi-static", "dynamic")]
    deadline = time.monotonic() + 90
    # Both workers are past their first messages (the log header alone is a few kB).
    while not all(p.exists() and p.stat().st_size > 20_000 for p in logs):
        assert time.monotonic() < deadline, "the runs never started writing their logs"
        time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    assert "interrupted" in stderr and "Traceback" not in stderr
    for p in logs:
        assert read_log(p).complete, p
    assert not (out / "compare.json").exists()
