"""`locoplan run` end to end in a subprocess: exit codes, metrics JSON, the MCAP log, and what a
user sees when the run breaks or is interrupted (shared/cli-contract.md)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from locoplan.log.reader import read_log

pytestmark = pytest.mark.closed_loop

LOCOPLAN = [sys.executable, "-m", "locoplan.cli"]
CONTRACT_KEYS = {
    "scenario", "strategy", "model", "sim_time", "wall_time", "real_time_factor", "completed",
    "completion_time", "fell", "yaw_difference_deg", "peak_torque_ratio", "peak_torque",
    "final_base", "objects", "mpc_solve_ms", "wbc_solve_ms", "expectations", "passed", "log",
}  # fmt: skip

SHORT_STAND = """version: 1
name: short-stand
tasks:
  - {action: stand, start: 0.0, duration: 1.0}
end: 1.0
expect:
  no_fall: true
  max_torque_ratio: 1.0
"""


def _write(tmp_path: Path, text: str, name: str = "task.yaml") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def _run(args: list[str], **kw: object) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*LOCOPLAN, *args], capture_output=True, text=True, timeout=300, check=False, **kw
    )  # type: ignore[call-overload]


def test_run_writes_metrics_and_log(tmp_path: Path) -> None:
    script = _write(tmp_path, SHORT_STAND)
    metrics_path = tmp_path / "m.json"
    res = _run(["run", str(script), "--out", str(tmp_path / "runs"), "--metrics-json",
                str(metrics_path)])  # fmt: skip
    assert res.returncode == 0, res.stderr
    m = json.loads(metrics_path.read_text())
    assert set(m) >= CONTRACT_KEYS
    assert m["passed"] and not m["fell"]
    assert m["scenario"] == "short-stand"
    assert m["expectations"]["no_fall"]["ok"]
    log = read_log(Path(m["log"]))
    assert log.complete
    assert log.scenario_text == SHORT_STAND
    assert log.metrics is not None and log.metrics["scenario"] == "short-stand"
    for topic in ("/tf", "/joint_states", "/contact/schedule", "/mpc/solution", "/wbc", "/events"):
        assert topic in log.topics, topic
    assert "Traceback" not in res.stderr


def test_failed_expectation_exits_1(tmp_path: Path) -> None:
    text = SHORT_STAND.replace("max_torque_ratio: 1.0", "max_torque_ratio: 0.01")
    res = _run(["run", str(_write(tmp_path, text)), "--out", str(tmp_path), "--quiet"])
    assert res.returncode == 1
    assert "Traceback" not in res.stderr + res.stdout


def test_bad_input_exits_2_with_position(tmp_path: Path) -> None:
    text = SHORT_STAND.replace("action: stand", "action: jump")
    script = _write(tmp_path, text)
    res = _run(["run", str(script), "--out", str(tmp_path)])
    assert res.returncode == 2
    assert f"{script}:4:" in res.stderr
    assert "allowed: stand, step, walk, turn, pick, drop, throw" in res.stderr
    assert "Traceback" not in res.stderr
    res = _run(["run", str(script), "--strategy", "sideways"])
    assert res.returncode == 2


def test_solver_failure_exits_3_with_readable_log(tmp_path: Path) -> None:
    # f_min above f_max makes every contact-force QP infeasible: no fallback can help.
    res = _run(["run", str(_write(tmp_path, SHORT_STAND)), "--out", str(tmp_path), "--f-min",
                "300", "--quiet"])  # fmt: skip
    assert res.returncode == 3
    assert "QP failed" in res.stderr
    assert "Traceback" not in res.stderr
    log = read_log(tmp_path / "short-stand.mcap")
    assert log.complete
    kinds = [msg["kind"] for _, msg in log.messages("/events")]
    assert "aborted" in kinds


def test_sigint_exits_130_with_readable_log(tmp_path: Path) -> None:
    text = SHORT_STAND.replace("duration: 1.0}\nend: 1.0", "duration: 60.0}\nend: 60.0")
    script = _write(tmp_path, text)
    proc = subprocess.Popen(
        [*LOCOPLAN, "run", str(script), "--out", str(tmp_path), "--quiet"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    log_path = tmp_path / "short-stand.mcap"
    deadline = time.monotonic() + 60
    while not (log_path.exists() and log_path.stat().st_size > 20_000):
        assert time.monotonic() < deadline, "the run never started writing its log"
        time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    assert "interrupted" in stderr
    assert "Traceback" not in stderr
    log = read_log(log_path)
    assert log.complete
    assert log.topics["/tf"].message_count > 10
    assert log.scenario_text == text
