"""`locoplan batch` end to end in a subprocess: exit codes, the JUnit report, the summary
table, crash and timeout isolation, the cache (shared/cli-contract.md, issue 7)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from typer.testing import CliRunner

from locoplan.cli import app

LOCOPLAN = [sys.executable, "-m", "locoplan.cli"]

STAND = """version: 1
name: {name}
tasks:
  - {{action: stand, start: 0.0, duration: {t}}}
end: {t}
expect:
  no_fall: true
  max_torque_ratio: {limit}
"""
MALFORMED = """version: 1
name: malformed
tasks:
  - {action: jump, start: 0.0, duration: 1.0}
"""


def _script(path: Path, name: str, t: float = 1.0, limit: float = 1.0) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(STAND.format(name=name, t=t, limit=limit))
    return path


def _batch(args: list[str], env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*LOCOPLAN, "batch", *args],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
        env={**os.environ, **(env or {})},
    )


def _suite(tmp_path: Path) -> Path:
    root = tmp_path / "suite"
    _script(root / "passing.yaml", "passing")
    # max_torque_ratio 0.001: standing needs ~13% of the knee limit, so this always fails.
    _script(root / "tight" / "impossible.yml", "impossible", limit=0.001)
    (root / "malformed.yaml").write_text(MALFORMED)
    return root


@pytest.mark.closed_loop
def test_pass_fail_and_malformed_then_cache(tmp_path: Path) -> None:
    root = _suite(tmp_path)
    out, report = tmp_path / "out", tmp_path / "report.xml"
    res = _batch([str(root), "--junit", str(report), "--out", str(out), "--jobs", "2"])
    assert res.returncode == 1, res.stderr
    assert "Traceback" not in res.stdout + res.stderr

    suite = ET.parse(report).getroot().find("testsuite")
    assert suite is not None
    cases = {c.get("name"): c for c in suite.iter("testcase")}
    assert set(cases) == {"passing.yaml", "impossible.yml", "malformed.yaml"}
    assert (suite.get("failures"), suite.get("errors")) == ("1", "1")
    assert cases["passing.yaml"].find("failure") is None
    assert cases["passing.yaml"].find("error") is None
    assert cases["impossible.yml"].get("classname") == "suite.tight"
    failure = cases["impossible.yml"].find("failure")
    assert failure is not None
    assert (failure.get("message") or "").startswith("max_torque_ratio: peak torque ratio ")
    error = cases["malformed.yaml"].find("error")
    assert error is not None
    # The message names the file, line 4 and column 14 (the action's value).
    assert (error.get("message") or "").startswith(f"{root / 'malformed.yaml'}:4:14: ")
    props = {p.get("name"): p.get("value") for p in cases["passing.yaml"].iter("property")}
    assert props["fell"] == "false" and props["passed"] == "true"
    assert float(props["peak_torque_ratio"] or "nan") < 1.0

    # Each run's MCAP and metrics JSON, mirroring the suite's folders.
    metrics = json.loads((out / "tight" / "impossible.json").read_text())
    assert metrics["scenario"] == "impossible" and not metrics["passed"]
    assert (out / "tight" / "impossible.mcap").is_file()
    assert (out / "passing.mcap").is_file() and (out / "passing.json").is_file()
    assert not (out / "malformed.mcap").exists()

    # The summary table: a row per script with its status and what failed.
    assert "1 passed, 1 failed, 1 error" in res.stdout
    assert "max_torque_ratio: peak torque ratio" in res.stdout
    assert "4:14: unknown action 'jump'" in res.stdout

    # Unchanged scripts and code: served from the cache, marked, same verdicts.
    start = time.perf_counter()
    again = _batch([str(root), "--junit", str(report), "--out", str(out)])
    elapsed = time.perf_counter() - start
    assert again.returncode == 1
    assert again.stdout.count("(cached)") == 2
    assert "2 from the cache" in again.stdout
    cached = {c.get("name"): c for c in ET.parse(report).getroot().iter("testcase")}
    for name in ("passing.yaml", "impossible.yml"):
        props = {p.get("name"): p.get("value") for p in cached[name].iter("property")}
        assert props["cached"] == "true"
    # No simulation: interpreter start-up, imports and validation take ~2 s here; 10 s
    # leaves room for a loaded machine (the runs themselves are reported as cached above).
    assert elapsed < 10.0


@pytest.mark.closed_loop
def test_crash_and_timeout_are_that_scripts_error(tmp_path: Path) -> None:
    root = tmp_path / "iso"
    _script(root / "crash.yaml", "crasher")
    _script(root / "hang.yaml", "hanger")
    _script(root / "ok.yaml", "fine", t=0.5)
    report = tmp_path / "r.xml"
    env = {"LOCOPLAN_TEST_CRASH": "crasher", "LOCOPLAN_TEST_HANG": "hanger"}
    # --timeout 10: long enough for the 0.5 s run on a loaded 2-core machine, short enough
    # to keep the test quick; the hung worker is stopped at 10 s.
    args = [str(root), "--out", str(tmp_path / "out"), "--junit", str(report), "--timeout", "10"]
    res = _batch([*args, "--jobs", "3"], env)
    assert res.returncode == 1, res.stderr
    assert "Traceback" not in res.stdout + res.stderr
    cases = {c.get("name"): c for c in ET.parse(report).getroot().iter("testcase")}
    crash, hang = cases["crash.yaml"].find("error"), cases["hang.yaml"].find("error")
    assert crash is not None and hang is not None
    assert (crash.get("message") or "").startswith("worker died (exit status 1)")
    assert (hang.get("message") or "").startswith("timed out after 10 s (--timeout)")
    assert cases["ok.yaml"].find("error") is None and cases["ok.yaml"].find("failure") is None


def test_bad_command_lines_exit_2(tmp_path: Path) -> None:
    # In process (nothing is simulated): the same command code, without interpreter start-up.
    (tmp_path / "empty").mkdir()
    runner = CliRunner()
    nothing = runner.invoke(app, ["batch", str(tmp_path / "empty")])
    assert nothing.exit_code == 2
    assert "no task scripts (*.yaml, *.yml) found" in nothing.stderr
    missing = runner.invoke(app, ["batch", str(tmp_path / "nope.yaml")])
    assert missing.exit_code == 2 and "no such file or directory" in missing.stderr
    bad_jobs = runner.invoke(app, ["batch", str(tmp_path), "--jobs", "0"])
    assert bad_jobs.exit_code == 2
    for res in (nothing, missing, bad_jobs):
        assert res.exception is None or isinstance(res.exception, SystemExit)


def test_fail_fast_with_a_malformed_script_runs_nothing(tmp_path: Path) -> None:
    root = tmp_path / "ff"
    _script(root / "a.yaml", "a")
    (root / "b.yaml").write_text(MALFORMED)
    res = _batch([str(root), "--fail-fast", "--out", str(tmp_path / "out")])
    assert res.returncode == 1
    assert "skipped" in res.stdout and "not run (--fail-fast)" in res.stdout
    assert not (tmp_path / "out" / "a.mcap").exists()
