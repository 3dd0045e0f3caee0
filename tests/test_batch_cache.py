"""The content-keyed result cache (locoplan/batch/cache.py)."""

from __future__ import annotations

import json
import time
from dataclasses import replace
from pathlib import Path

from locoplan.batch.cache import (
    ResultCache,
    cache_key,
    code_fingerprint,
    robot_fingerprint,
)
from locoplan.batch.job import Job, Outcome
from locoplan.sim.run import RunOptions

TEXT = "version: 1\nname: t\ntasks:\n  - {action: stand, start: 0.0, duration: 1.0}\n"


def _job(text: str = TEXT, **options: object) -> Job:
    return Job("t.yaml", "t", "t.yaml", text, replace(RunOptions(), **options))  # type: ignore[arg-type]


def test_code_fingerprint_is_stable_and_quick() -> None:
    start = time.perf_counter()
    first = code_fingerprint()
    elapsed = time.perf_counter() - start
    assert first == code_fingerprint()
    assert len(first) == 64
    # Hashing ~100 small source files; a generous bound that still catches hashing a venv.
    assert elapsed < 2.0


def test_key_changes_with_text_code_options_and_robot() -> None:
    base = cache_key(_job(), "code")
    assert base == cache_key(_job(), "code")
    assert base != cache_key(_job(TEXT + "# comment\n"), "code")  # exact text, comments too
    assert base != cache_key(_job(), "other code")
    assert base != cache_key(_job(strategy="quasi-static"), "code")
    assert base != cache_key(_job(out_dir=Path("elsewhere")), "code")
    assert base != cache_key(_job(), "code", robot="robot digest")


def test_robot_fingerprint_follows_the_robot_folder(tmp_path: Path) -> None:
    robot = tmp_path / "bot" / "robot.yaml"
    robot.parent.mkdir()
    robot.write_text("name: bot\n")
    (robot.parent / "bot.xml").write_text("<mujoco/>\n")
    before = robot_fingerprint(robot)
    (robot.parent / "bot.xml").write_text("<mujoco model='x'/>\n")
    assert robot_fingerprint(robot) != before
    assert robot_fingerprint(None) == "-"


def _finished(tmp_path: Path, status: str = "failed") -> Outcome:
    log = tmp_path / "t.mcap"
    log.write_bytes(b"mcap")
    metrics = {"scenario": "t", "peak_torque_ratio": 0.13, "log": str(log), "expectations": {}}
    return Outcome("t.yaml", status, metrics, "max_torque_ratio: ...", wall_time=1.5)  # type: ignore[arg-type]


def test_round_trip_marks_cached(tmp_path: Path) -> None:
    cache = ResultCache(tmp_path / ".cache")
    outcome = _finished(tmp_path)
    cache.put("k", outcome)
    hit = cache.get("k", "renamed.yaml")
    assert hit is not None
    assert hit.cached and hit.job_id == "renamed.yaml"
    assert (hit.status, hit.message, hit.wall_time) == ("failed", outcome.message, 1.5)
    assert dict(hit.metrics or {}) == dict(outcome.metrics or {})
    assert cache.get("other", "t.yaml") is None


def test_no_hit_when_the_log_is_gone_or_the_entry_is_broken(tmp_path: Path) -> None:
    cache = ResultCache(tmp_path / ".cache")
    outcome = _finished(tmp_path, "passed")
    cache.put("k", outcome)
    Path(str((outcome.metrics or {})["log"])).unlink()
    assert cache.get("k", "t.yaml") is None
    (tmp_path / ".cache" / "bad.json").write_text("{not json")
    assert cache.get("bad", "t.yaml") is None
    (tmp_path / ".cache" / "old.json").write_text(json.dumps({"format": 0}))
    assert cache.get("old", "t.yaml") is None


def test_errors_are_not_stored(tmp_path: Path) -> None:
    cache = ResultCache(tmp_path / ".cache")
    cache.put("k", Outcome("t.yaml", "error", message="worker died"))
    cache.put("s", Outcome("t.yaml", "skipped"))
    assert not (tmp_path / ".cache").exists()
