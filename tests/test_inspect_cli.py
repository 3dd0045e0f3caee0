"""`locoplan inspect LOG`: scenario, metrics, topics and duration from the log alone, for a
finished run, a run that broke, a log cut short by a killed writer, and files that are not
logs (exit 2). In process through typer's runner (the CLI is thin; `test_render_cli` covers
the subprocess path)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from locoplan.cli import app
from locoplan.exceptions import SolverFailure
from locoplan.log.reader import read_log
from locoplan.log.writer import RunLogWriter
from locoplan.plan import compile_plan
from locoplan.report.inspect_table import run_status
from locoplan.robot.description import load_robot_description
from locoplan.scenario import load_scenario_file
from locoplan.sim.loop import ClosedLoop
from locoplan.sim.run import RunOptions, controller_settings, run_scenario, scene_for

pytestmark = pytest.mark.closed_loop

SHORT_STAND = """version: 1
name: short-stand
tasks:
  - {action: stand, start: 0.0, duration: 0.5}
  - {action: step, start: 0.5, duration: 0.5}
end: 1.0
expect:
  no_fall: true
"""


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A finished run's log, an aborted one (solver failure at t = 0) and the file a killed
    writer leaves: a copy of a log taken while its writer is still open, after a flush (every
    chunk written so far, no summary, no metrics), which is what SIGKILL at that instant
    leaves on disk (`test_render_video` kills a real process)."""
    tmp = tmp_path_factory.mktemp("inspect")
    script = tmp / "stand.yaml"
    script.write_text(SHORT_STAND)
    loaded = load_scenario_file(script)
    finished = run_scenario(loaded.scenario, loaded.text, RunOptions(out_dir=tmp / "ok"))
    assert finished.log_path is not None
    with pytest.raises(SolverFailure):
        run_scenario(loaded.scenario, loaded.text, RunOptions(out_dir=tmp / "broke", f_min=300.0))
    scenario = loaded.scenario
    desc = load_robot_description(scenario.robot)
    open_log = tmp / "open.mcap"
    killed = tmp / "killed.mcap"
    with RunLogWriter(
        open_log, scenario_name=scenario.name, scenario_text=loaded.text, flush_interval_s=0.01
    ) as writer:
        loop = ClosedLoop(
            scene_for(scenario, desc),
            desc,
            compile_plan(scenario),
            controller_settings(scenario, RunOptions()),
            log=writer,
        )
        loop.run(0.5)
        writer.flush()
        shutil.copyfile(open_log, killed)
    return {
        "finished": finished.log_path,
        "broke": tmp / "broke" / "short-stand.mcap",
        "killed": killed,
    }


def _inspect(*args: str) -> tuple[int, str]:
    result = CliRunner().invoke(app, ["inspect", *args], terminal_width=200)
    return result.exit_code, result.output


def test_finished_run_shows_scenario_metrics_topics_and_duration(logs: dict[str, Path]) -> None:
    code, text = _inspect(str(logs["finished"]))
    assert code == 0, text
    assert "finished" in text and "short-stand" in text
    assert "scenario short-stand: 2 tasks, end 1 s" in text
    assert "stand" in text and "step" in text
    assert "expect no_fall" in text  # the metrics table
    log = read_log(logs["finished"])
    for topic, info in log.topics.items():
        assert topic in text
        assert str(info.message_count) in text
    assert "/sim/qpos" in text and "/scene/robot" in text
    assert "s of simulation" in text


def test_broken_run_says_it_was_aborted_and_why(logs: dict[str, Path]) -> None:
    code, text = _inspect(str(logs["broke"]))
    assert code == 0, text
    assert "aborted" in text and "MPC QP failed" in text
    assert "metrics: none" in text
    assert "scenario short-stand" in text  # the scenario is written when the log opens


def test_killed_writers_log_is_shown_as_incomplete(logs: dict[str, Path]) -> None:
    log = read_log(logs["killed"])
    assert not log.complete and run_status(log) == "incomplete"
    code, text = _inspect(str(logs["killed"]))
    assert code == 0, text
    assert "incomplete" in text and "the writer was killed" in text
    assert "scenario short-stand" in text and "metrics: none" in text
    # Flushed every 10 ms of wall time: nearly all of the 0.5 s survived.
    assert log.end_time is not None and log.end_time > 0.4
    assert f"{log.end_time:.3f}" in text
    assert log.topics["/sim/qpos"].message_count > 40


def test_json_summary(logs: dict[str, Path]) -> None:
    code, text = _inspect(str(logs["finished"]), "--json")
    assert code == 0, text
    summary = json.loads(text)
    assert summary["complete"] and summary["status"] == "finished"
    assert summary["scenario"] == "short-stand"
    assert summary["metrics"]["scenario"] == "short-stand"
    assert summary["topics"]["/sim/qpos"]["count"] > 90  # 1 s at 100 Hz, plus t = 0


def test_not_a_log_exits_2(tmp_path: Path) -> None:
    text_file = tmp_path / "notes.mcap"
    text_file.write_text("hello\n")
    code, text = _inspect(str(text_file))
    assert code == 2 and "not a readable MCAP log" in text
    code, text = _inspect(str(tmp_path / "missing.mcap"))
    assert code == 2 and "no such file" in text
    code, text = _inspect(str(tmp_path))
    assert code == 2 and "directory" in text
    empty = tmp_path / "empty.mcap"
    empty.write_bytes(b"")
    code, text = _inspect(str(empty))
    assert code == 2
