"""Stopping at any moment (issue 13, part 2): SIGINT ends with 130 and SIGTERM with 143, the
MCAP closed and complete up to that tick, never an internal error or a traceback, in `run`
(while the kernels load, while simulating, just as the log appears), `compare`, inside a batch
worker and in a batch's parent; and `--max-sim-time`."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from locoplan import interrupt
from locoplan.log.reader import read_log

pytestmark = pytest.mark.closed_loop

LOCOPLAN = [sys.executable, "-m", "locoplan"]
ENV = {**os.environ, "PYTHONUNBUFFERED": "1"}
LONG = (
    "version: 1\nname: {name}\ntasks:\n  - {{action: stand, start: 0.0, duration: {t}}}\nend: {t}\n"
)
ALLOW = ["--max-sim-time", "8000"]


def _script(folder: Path, name: str, t: float = 7200.0) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.yaml"
    path.write_text(LONG.format(name=name, t=t))
    return path


def _start(args: list[str], cwd: Path) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [*LOCOPLAN, *args], cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env=ENV,
    )  # fmt: skip


def _wait_for(condition: Callable[[], bool], what: str, seconds: float = 90.0) -> None:
    deadline = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.05)


def _catches(pid: int, sig: signal.Signals) -> bool:
    """Whether the process has a handler for `sig`: the SigCgt mask of /proc/PID/status
    (Linux); elsewhere, True after the 0.7 s such a process takes on an idle machine."""
    status = Path(f"/proc/{pid}/status")
    if not status.exists():
        time.sleep(0.7)
        return True
    for line in status.read_text().splitlines():
        if line.startswith("SigCgt:"):
            return bool(int(line.split()[1], 16) >> (int(sig) - 1) & 1)
    return False


def _size(path: Path) -> int:
    return path.stat().st_size if path.exists() else 0


def _assert_clean(stderr: str) -> None:
    assert "internal error" not in stderr, stderr
    assert "Traceback" not in stderr, stderr
    assert "SystemError" not in stderr, stderr


def _inspect_ok(log: Path) -> dict[str, object]:
    res = subprocess.run(
        [*LOCOPLAN, "inspect", str(log), "--json"], capture_output=True, text=True, timeout=120,
        check=False,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr
    return dict(json.loads(res.stdout))


EXPECTED = {signal.SIGINT: (130, "interrupted"), signal.SIGTERM: (143, "terminated (SIGTERM)")}


@pytest.mark.parametrize(
    ("moment", "sig"),
    [
        ("warm-up", signal.SIGTERM),
        ("warm-up", signal.SIGINT),
        ("log-appears", signal.SIGTERM),
        ("simulating", signal.SIGINT),
        ("simulating", signal.SIGTERM),
    ],
)
def test_run_stops_cleanly(tmp_path: Path, moment: str, sig: signal.Signals) -> None:
    _script(tmp_path, "long")
    log = tmp_path / "runs" / "long.mcap"
    proc = _start(["run", "long.yaml", "--out", "runs", "--quiet", *ALLOW], tmp_path)
    if moment == "warm-up":
        # The command has set its handlers (0.3-0.8 s after start on this machine: a fixed
        # 0.7 s from the start sometimes came first, exit -15), loaded its script (a few
        # tenths of a second) and is importing the simulator and loading (or compiling) its
        # kernels, 1 s or more before the first tick. SIGTERM's handler tells: Python itself
        # catches SIGINT from its start, locoplan sets both at once.
        _wait_for(lambda: _catches(proc.pid, signal.SIGTERM), "the signal handlers")
        time.sleep(0.7)
    elif moment == "log-appears":
        _wait_for(lambda: _size(log) > 0, "the log to appear")
    else:
        _wait_for(lambda: _size(log) > 300_000, "the log to grow")
    proc.send_signal(sig)
    _, stderr = proc.communicate(timeout=60)
    code, word = EXPECTED[sig]
    assert proc.returncode == code, stderr
    assert word in stderr
    _assert_clean(stderr)
    if moment == "warm-up" and not log.exists():
        assert "before its log was opened" in stderr  # nothing to read, and it says so
        return
    summary = _inspect_ok(log)
    assert summary["status"] == "aborted", summary
    parsed = read_log(log)
    assert parsed.complete  # closed with summary and footer, not a killed file
    if moment == "simulating":
        assert parsed.topics["/tf"].message_count > 50


def test_compare_stops_both_runs(tmp_path: Path) -> None:
    _script(tmp_path, "cmp")
    out = tmp_path / "out"
    logs = [out / "cmp-quasi-static.mcap", out / "cmp-dynamic.mcap"]
    proc = _start(["compare", "cmp.yaml", "--out", "out", "--jobs", "2", "--quiet", *ALLOW],
                  tmp_path)  # fmt: skip
    _wait_for(lambda: all(_size(p) > 100_000 for p in logs), "both logs to grow", 120)
    proc.send_signal(signal.SIGTERM)
    _, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 143, stderr
    assert "terminated (SIGTERM)" in stderr
    _assert_clean(stderr)
    for p in logs:
        assert read_log(p).complete, p
        assert _inspect_ok(p)["status"] == "aborted"


def test_batch_worker_timeout_and_parent_interrupt(tmp_path: Path) -> None:
    scripts = tmp_path / "scripts"
    _script(scripts, "a-short", 0.5)
    _script(scripts, "b-long")
    out = tmp_path / "out"
    # A worker stopped by the pool's timeout (SIGTERM) closes its log; the batch goes on.
    res = subprocess.run(
        [*LOCOPLAN, "batch", "scripts", "--out", "out", "--jobs", "1", "--timeout", "8",
         "--no-cache", *ALLOW],
        cwd=tmp_path, capture_output=True, text=True, timeout=180, check=False, env=ENV,
    )  # fmt: skip
    assert res.returncode == 1, res.stderr
    _assert_clean(res.stderr)
    assert "timed out after 8 s" in res.stdout + res.stderr
    log = out / "b-long.mcap"
    assert read_log(log).complete
    assert _inspect_ok(log)["status"] == "aborted"

    # SIGINT to the parent: it stops its worker (which closes its log), prints the summary
    # of what finished and exits 130.
    proc = _start(["batch", "scripts", "--out", "out2", "--jobs", "1", "--no-cache", *ALLOW],
                  tmp_path)  # fmt: skip
    log2 = tmp_path / "out2" / "b-long.mcap"
    _wait_for(lambda: _size(log2) > 100_000, "the long run's log to grow", 120)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    _assert_clean(stderr)
    assert "1 of 2 runs finished" in stderr
    assert "a-short" in stdout and "b-long" in stdout  # the summary table
    assert "interrupted (SIGINT)" in stdout + stderr
    assert (tmp_path / "out2" / "a-short.json").exists()
    assert read_log(log2).complete


def test_max_sim_time_refuses_long_scripts(tmp_path: Path) -> None:
    _script(tmp_path, "year", 3.2e7)
    res = subprocess.run(
        [*LOCOPLAN, "validate", "year.yaml"], cwd=tmp_path, capture_output=True, text=True,
        timeout=60, check=False,
    )  # fmt: skip
    assert res.returncode == 2
    line = res.stdout.strip()
    assert line.startswith("year.yaml:5:6: end: 3.2e+07 s of simulated time"), line
    assert "more than the 3600 s allowed" in line and "about 123.5 days of wall time at ~3x" in line
    assert "--max-sim-time" in line
    ok = subprocess.run(
        [*LOCOPLAN, "validate", "year.yaml", "--max-sim-time", "4e7"], cwd=tmp_path,
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert ok.returncode == 0, ok.stdout
    run = subprocess.run(
        [*LOCOPLAN, "run", "year.yaml", "--quiet"], cwd=tmp_path, capture_output=True,
        text=True, timeout=60, check=False,
    )  # fmt: skip
    assert run.returncode == 2 and "year.yaml:5:6:" in run.stderr
    assert not (tmp_path / "runs").exists()  # nothing simulated


def test_max_sim_time_without_end_points_at_the_last_task(tmp_path: Path) -> None:
    from locoplan.scenario import load_scenario_file
    from locoplan.scenario.limits import sim_time_issue

    text = (
        "version: 1\nname: t\ntasks:\n  - {action: stand, start: 0.0, duration: 1.0}\n"
        "  - {action: stand, start: 1.0, duration: 5000.0}\n"
    )
    loaded = load_scenario_file("t.yaml", text)
    issue = sim_time_issue(loaded)
    assert issue is not None and (issue.line, issue.column) == (5, 5)
    assert "last task ends" in issue.message
    assert sim_time_issue(loaded, 6000.0) is None


def test_signals_only_set_the_flag_while_deferring() -> None:
    restore = interrupt.install()
    try:
        with interrupt.deferring():
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.01)  # the handler runs here and returns
            assert interrupt.pending() == signal.SIGTERM
        with pytest.raises(interrupt.Interrupted) as caught:
            interrupt.check()
        assert caught.value.code == 143 and str(caught.value) == "interrupted by SIGTERM"
        interrupt.STATE.signum = 0
        with pytest.raises(interrupt.Interrupted) as at_once:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)
        assert at_once.value.code == 130
    finally:
        restore()
        interrupt.STATE.signum = 0


def test_interruption_follows_the_cause_chain() -> None:
    try:
        try:
            raise interrupt.Interrupted(signal.SIGTERM)
        except interrupt.Interrupted as exc:
            raise SystemError("CPUDispatcher(...) returned a result with an exception set") from exc
    except SystemError as outer:
        assert interrupt.interruption(outer) == 143
    assert interrupt.interruption(KeyboardInterrupt()) == 130
    assert interrupt.interruption(ValueError("x")) is None
    import pickle

    back = pickle.loads(pickle.dumps(interrupt.Interrupted(signal.SIGINT)))
    assert isinstance(back, interrupt.Interrupted) and back.code == 130
