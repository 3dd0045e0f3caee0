"""Tests of locoplan.log.reader: complete files, files left by a SIGKILLed writer, truncated
files, and their recovery into indexed files."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from locoplan.log import (
    JsonDecoderFactory,
    LogReadError,
    RunLogWriter,
    log_summary,
    read_log,
    recover_log,
)

FLUSH_INTERVAL_S = 0.5
# A SIGKILL may land just before a flush was due, and the child may be descheduled for a
# while on a shared 2-core machine: allow 0.3 s on top of the flush interval.
KILL_SLACK_S = 0.3

_CHILD = textwrap.dedent(
    """
    import sys, time
    import numpy as np
    from locoplan.log import RunLogWriter

    names = [f"j{i}" for i in range(16)]
    q = np.linspace(-1.0, 1.0, 16)
    w = RunLogWriter(
        sys.argv[1],
        scenario_name="killed",
        scenario_text="name: killed\\n",
        metadata={"strategy": "dynamic"},
        flush_interval_s=float(sys.argv[2]),
    )
    print("ready", flush=True)
    k = 0
    while True:
        t = k * 1e-3
        w.joint_states(t, names, q, q, q)
        if k % 10 == 0:
            # CLOCK_MONOTONIC is shared by all processes on Linux: the parent compares it.
            w.json("/wall", t, {"wall": time.monotonic(), "k": k})
        k += 1
        time.sleep(2e-4)
    """
)


def _write_until_killed(path: Path, seconds: float) -> float:
    """Run the writer child, SIGKILL it `seconds` after it opened the log; the kill time."""
    proc = subprocess.Popen(
        [sys.executable, "-c", _CHILD, str(path), str(FLUSH_INTERVAL_S)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout is not None
        line = proc.stdout.readline()
        assert line.strip() == "ready", proc.stderr.read() if proc.stderr else ""
        time.sleep(seconds)
        killed_at = time.monotonic()
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.kill()
        proc.wait(timeout=10)
    return killed_at


@pytest.fixture(scope="module")
def killed_log(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, float]:
    path = tmp_path_factory.mktemp("killed") / "killed.mcap"
    return path, _write_until_killed(path, 1.5)


def test_killed_file_is_not_readable_by_the_indexed_reader(killed_log: tuple[Path, float]) -> None:
    path, _ = killed_log
    with open(path, "rb") as f, pytest.raises(Exception):  # noqa: B017 -- any mcap failure
        make_reader(f).get_summary()


def test_killed_file_reads_up_to_the_last_flush(killed_log: tuple[Path, float]) -> None:
    path, killed_at = killed_log
    log = read_log(path)
    assert not log.complete
    assert log.scenario_name == "killed"
    assert log.metadata["locoplan"]["strategy"] == "dynamic"
    assert log.scenario_text == "name: killed\n"
    assert "run_end" not in log.metadata
    wall = [(t, m["wall"], m["k"]) for t, m in log.messages("/wall")]
    assert len(wall) > 10
    assert [k for _, _, k in wall] == list(range(0, 10 * len(wall), 10))  # nothing skipped
    lost = killed_at - wall[-1][1]
    assert 0.0 < lost < FLUSH_INTERVAL_S + KILL_SLACK_S
    joint_msgs = list(log.messages("/joint_states"))
    assert log.topics["/joint_states"].message_count == len(joint_msgs)
    np.testing.assert_array_equal(  # exact: doubles pass through protobuf unchanged
        [j.position for j in joint_msgs[-1][1].joints], np.linspace(-1.0, 1.0, 16)
    )
    assert log.end_time == max(t for t, _ in joint_msgs)


def test_recover_log_makes_an_indexed_file(killed_log: tuple[Path, float]) -> None:
    path, _ = killed_log
    before = read_log(path)
    out = recover_log(path)
    assert out == path.with_name("killed.recovered.mcap")
    with open(out, "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        assert sum(1 for _ in reader.iter_messages()) > 0  # every chunk CRC checks out
        summary = reader.get_summary()
        assert summary is not None and summary.statistics is not None
        assert {c.topic for c in summary.channels.values()} == set(before.topics)
        assert summary.statistics.message_count == sum(
            i.message_count for i in before.topics.values()
        )
    after = read_log(out)
    assert after.complete
    assert after.attachments == before.attachments
    assert after.metadata["locoplan"] == before.metadata["locoplan"]
    assert after.metadata["recovered"]["source"] == str(path)
    assert {k: v.message_count for k, v in after.topics.items()} == {
        k: v.message_count for k, v in before.topics.items()
    }
    assert list(after.messages("/wall")) == list(before.messages("/wall"))
    assert (after.start_time, after.end_time) == (before.start_time, before.end_time)


def test_recover_log_in_place(killed_log: tuple[Path, float], tmp_path: Path) -> None:
    path = tmp_path / "copy.mcap"
    shutil.copy(killed_log[0], path)
    count = read_log(path).topics["/wall"].message_count
    assert recover_log(path, path) == path
    log = read_log(path)
    assert log.complete and log.topics["/wall"].message_count == count
    assert [p.name for p in tmp_path.iterdir()] == ["copy.mcap"]  # no temporary left behind


def test_log_summary_of_killed_and_complete_files(
    killed_log: tuple[Path, float], tmp_path: Path
) -> None:
    summary = log_summary(killed_log[0])
    assert summary["complete"] is False
    assert summary["status"] is None
    assert summary["scenario"] == "killed"
    assert summary["metrics"] is None
    assert summary["topics"]["/joint_states"]["schema"] == "foxglove.JointStates"

    path = tmp_path / "done.mcap"
    with RunLogWriter(path, scenario_name="done", scenario_text="x: 1\n") as w:
        w.json("/a", 0.5, {"v": 1.0})
        w.json("/a", 2.5, {"v": 2.0})
        w.finish({"completed": True})
    summary = log_summary(path)
    assert summary["complete"] is True
    assert summary["status"] == "finished"
    assert summary["duration"] == 2.0
    assert summary["message_count"] == 2
    assert summary["topics"] == {"/a": {"schema": "locoplan.a", "count": 2}}
    assert summary["attachments"] == ["metrics.json", "scenario.yaml"]
    assert summary["metrics"] == {"completed": True}


def _small_log(path: Path) -> None:
    with RunLogWriter(path, scenario_name="small", scenario_text="a: 1\n") as w:
        for k in range(200):
            w.json("/a", k * 1e-3, {"k": k, "v": np.arange(3.0) * k})
            if k % 50 == 49:
                w.flush()  # several chunks, so truncation lands in different places
        w.finish({"n": 200})


def test_every_truncation_reads_or_fails_cleanly(tmp_path: Path) -> None:
    """A file cut at any byte either reads (a prefix of the messages) or, when not even the
    header survived, raises LogReadError."""
    full = tmp_path / "full.mcap"
    _small_log(full)
    data = full.read_bytes()
    previous = -1
    cut = tmp_path / "cut.mcap"
    for size in [*range(0, 64, 7), *range(64, len(data), max(1, len(data) // 60)), len(data)]:
        cut.write_bytes(data[:size])
        try:
            log = read_log(cut)
        except LogReadError:
            assert size < 200, f"a {size}-byte prefix should hold the header"
            continue
        count = log.topics["/a"].message_count if "/a" in log.topics else 0
        ks = [m["k"] for _, m in log.messages("/a")] if count else []
        assert ks == list(range(count))
        assert count >= previous
        previous = count
        recovered = recover_log(cut, tmp_path / "rec.mcap")
        with open(recovered, "rb") as f:
            assert make_reader(f).get_summary() is not None
    assert previous == 200


def test_non_mcap_and_missing_files(tmp_path: Path) -> None:
    junk = tmp_path / "junk.mcap"
    junk.write_text("name: not an mcap file\n" * 10)
    with pytest.raises(LogReadError, match=r"junk\.mcap"):
        read_log(junk)
    with pytest.raises(FileNotFoundError):
        read_log(tmp_path / "missing.mcap")


def test_unknown_topic_raises_key_error(tmp_path: Path) -> None:
    path = tmp_path / "k.mcap"
    with RunLogWriter(path, scenario_name="k", scenario_text="") as w:
        w.json("/a", 0.0, {"v": 1.0})
    with pytest.raises(KeyError, match="/b"):
        read_log(path).messages("/b")


def test_json_decoder_factory_only_takes_json() -> None:
    factory = JsonDecoderFactory()
    assert factory.decoder_for("protobuf", None) is None
    decode = factory.decoder_for("json", None)
    assert decode is not None and decode(b'{"a": [1, 2]}') == {"a": [1, 2]}
