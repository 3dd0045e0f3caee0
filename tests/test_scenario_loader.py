"""locoplan.scenario.loader: load_scenario / load_scenario_file and LoadedScenario."""

from __future__ import annotations

import os
import re
import textwrap
from pathlib import Path

import pytest

from locoplan.exceptions import ScenarioError
from locoplan.scenario import (
    DropTask,
    LoadedScenario,
    PickTask,
    Scenario,
    TurnTask,
    load_scenario,
    load_scenario_file,
)

DATA = Path(__file__).parent / "data" / "scenarios"
FORMAT_DOC = Path("/work/shared/scenario-format.md")
REPO = Path(__file__).resolve().parent.parent


def issues_of(text: str, source: str = "t.yaml") -> list[str]:
    with pytest.raises(ScenarioError) as info:
        load_scenario(source, text)
    return [str(issue) for issue in info.value.issues]


def test_format_example_fixture_loads_with_the_documented_values() -> None:
    loaded = load_scenario_file(DATA / "good" / "format-example.yaml")
    s = loaded.scenario
    assert s.name == "package-transfer"
    assert [t.action for t in s.tasks] == ["turn", "pick", "turn", "drop"]
    assert isinstance(s.tasks[0], TurnTask) and s.tasks[0].angle == 90.0  # degrees, as written
    assert isinstance(s.tasks[3], DropTask) and s.tasks[3].onto == "conveyor"
    assert s.objects["package"].size == [0.25, 0.20, 0.15]
    assert s.fixtures["conveyor"].speed == 0.2
    assert s.fixtures["table"].top_height == 0.62
    assert s.expect.placed == {"package": "conveyor"}
    assert s.expect.max_yaw_difference == 60.0
    assert s.strategy == "dynamic" and s.model == "external-force" and s.robot == "hector"
    # `end` not given: the last task's end (3.2 + 0.8) plus the settle time.
    assert s.end is None
    assert s.end_time == pytest.approx(4.0 + Scenario.SETTLE_TIME, abs=1e-12)  # float sum


def _yaml_blocks(markdown: str) -> list[str]:
    return re.findall(r"```yaml\n(.*?)```", markdown, flags=re.DOTALL)


@pytest.mark.skipif(not FORMAT_DOC.exists(), reason="shared/scenario-format.md not available")
def test_format_page_snippets_validate_exactly_as_written() -> None:
    """Assemble a script from the format page's own snippets, byte for byte, and load it."""
    blocks = _yaml_blocks(FORMAT_DOC.read_text(encoding="utf-8"))
    objects = [b for b in blocks if "shape:" in b]
    fixtures = [b for b in blocks if "kind:" in b]
    tasks = [b for b in blocks if b.startswith("tasks:")]
    expect = [b for b in blocks if b.startswith("expect:")]
    assert len(objects) == len(fixtures) == len(tasks) == len(expect) == 1
    text = (
        "version: 1\nname: format-page\n"
        + "objects:\n"
        + textwrap.indent(objects[0], "  ")
        + "fixtures:\n"
        + textwrap.indent(fixtures[0], "  ")
        + tasks[0]
        + expect[0]
    )
    s = load_scenario("format-page.yaml", text)
    assert [t.action for t in s.tasks] == ["turn", "pick", "turn", "drop"]
    # The fixture file in tests/data holds the same snippets, line for line.
    fixture_lines = (DATA / "good" / "format-example.yaml").read_text().splitlines()
    fixture_stripped = {line.strip() for line in fixture_lines}
    for block in (objects[0], fixtures[0], tasks[0], expect[0]):
        for line in block.splitlines():
            assert line.strip() in fixture_stripped, line


def test_loaded_scenario_keeps_path_and_exact_text() -> None:
    path = DATA / "good" / "all-options.yaml"
    loaded = load_scenario_file(path)
    assert isinstance(loaded, LoadedScenario)
    assert loaded.path == path
    assert loaded.text == path.read_text(encoding="utf-8")
    assert loaded.label == str(path)
    assert loaded.robot_path is None  # built-in robot
    s = loaded.scenario
    assert s.strategy == "quasi-static" and s.model == "combined"
    assert s.mpc.horizon == 16 and s.gait.swing == 0.2
    assert s.robot_start.position == [-0.5, 0.25] and s.robot_start.yaw == 15.0
    # The merge key copies the anchored object and overrides its position.
    assert s.objects["ball2"].size == [0.08] and s.objects["ball2"].position[0] == 1.2
    assert s.description == "Walk to a platform, pick a ball, place it at a point, then stand.\n"


def test_robot_path_is_resolved_against_the_script_folder() -> None:
    loaded = load_scenario_file(DATA / "good" / "repick-and-throw.yaml")
    assert loaded.robot_path is not None
    assert loaded.robot_path.resolve() == REPO / "robots" / "hector" / "hector.xml"


def test_text_argument_str_and_bytes_and_stdin_label() -> None:
    text = (DATA / "good" / "minimal.yaml").read_text()
    assert load_scenario("anything.yaml", text).name == "minimal"
    assert load_scenario("anything.yaml", text.encode()).name == "minimal"
    loaded = load_scenario_file("-", text)
    assert loaded.path is None and loaded.label == "<stdin>" and loaded.text == text
    assert "<stdin>:1:10: invalid version 2; allowed: 1" in issues_of("version: 2\n", "-")


def test_bom_and_crlf_line_endings() -> None:
    text = (
        "\ufeffversion: 1\r\nname: crlf\r\ntasks:\r\n  - {action: jump, start: 0, duration: 1}\r\n"
    )
    assert issues_of(text) == [
        "t.yaml:4:14: unknown action 'jump'; allowed: stand, step, walk, turn, pick, drop, throw"
    ]
    assert load_scenario("t.yaml", text.replace("jump", "stand")).name == "crlf"


def test_structural_and_semantic_issues_are_reported_together() -> None:
    """An error outside the sections the semantic checks read does not hide their issues."""
    text = textwrap.dedent(
        """\
        version: 1
        name: both
        mpc: {horizon: 1}
        objects:
          box: {shape: box, size: [0.2, 0.2, 0.2], mass: 1, position: [0, 0.5, 0.7]}
        tasks:
          - {action: drop, object: box, at: [0, 0, 1], start: 0, duration: 1}
        """
    )
    assert issues_of(text) == [
        "t.yaml:3:16: horizon must be >= 2, got 1",
        "t.yaml:7:5: cannot drop 'box' at 0 s: it is not held then; no pick of it comes before "
        "(an object is held from the end of its pick until a drop or throw starts)",
    ]


def test_semantic_checks_wait_for_valid_tasks() -> None:
    """A task that does not validate would make holding checks guess: they are skipped."""
    text = textwrap.dedent(
        """\
        version: 1
        name: wait
        objects:
          box: {shape: box, size: [0.2, 0.2, 0.2], mass: 1, position: [0, 0.5, 0.7]}
        tasks:
          - {action: pick, object: box, start: 0, duration: -1}
          - {action: drop, object: box, at: [0, 0, 1], start: 2, duration: 1}
        """
    )
    assert issues_of(text) == ["t.yaml:6:53: duration must be > 0 s, got -1"]


def test_issues_are_sorted_by_position_and_carry_the_label() -> None:
    text = "tasks: 5\nversion: 3\nfoo: 1\n"
    issues = issues_of(text, "dir/x.yaml")
    assert issues == [
        "dir/x.yaml:1:1: missing key 'name' at the top level; required: version, name, tasks",
        "dir/x.yaml:1:8: expected a list, got 5",
        "dir/x.yaml:2:10: invalid version 3; allowed: 1",
        "dir/x.yaml:3:1: unknown key 'foo' at the top level; allowed: version, name, "
        "description, robot, robot_start, strategy, model, mpc, gait, objects, fixtures, "
        "tasks, end, expect",
    ]


def test_null_values_point_at_their_key() -> None:
    text = "version: 1\nname: n\ntasks:\n  - action: pick\n    object:\n"
    text += "    start: 0\n    duration: 1\n"
    assert issues_of(text) == ["t.yaml:5:5: expected a string, got null; quote it to make it text"]


def test_strict_numbers_booleans_and_version() -> None:
    base = "version: 1\nname: s\ntasks: [{action: stand, start: 0, duration: 1}]\n"
    assert issues_of(base.replace("version: 1", "version: true")) == [
        "t.yaml:1:10: version must be the integer 1"
    ]
    assert issues_of(base + "end: '5'\n") == [
        "t.yaml:4:6: expected a number, got '5'; write numbers without quotes"
    ]
    assert issues_of(base + "expect: {no_fall: 1}\n") == [
        "t.yaml:4:19: expected true or false, got 1"
    ]
    assert issues_of(base + "name: 12\n")[0].startswith("t.yaml:4:1: duplicate key 'name'")
    assert issues_of(base.replace("name: s", "name: 12")) == [
        "t.yaml:2:7: expected a string, got 12; quote it to make it text"
    ]
    # An integer is a fine float.
    assert load_scenario("t.yaml", base).tasks[0].duration == 1.0


def test_vectors_name_their_length() -> None:
    text = (
        "version: 1\nname: v\n"
        "tasks: [{action: throw, object: b, velocity: 3, start: 0, duration: 1},"
        " {action: walk, distance: [1, 2, 3], start: 2, duration: 1}]\n"
    )
    assert issues_of(text) == [
        "t.yaml:3:46: expected a list of 3 numbers, got 3",
        "t.yaml:3:98: distance needs 2 values, got 3",
    ]


def test_repick_after_drop_and_file_order_do_not_matter() -> None:
    s = load_scenario(DATA / "good" / "repick-and-throw.yaml")
    picks = [t for t in s.tasks if isinstance(t, PickTask)]
    assert [p.hands for p in picks] == ["both", "left"]


def test_a_relative_robot_path_is_resolved_beside_the_script(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The robot file is named relative to the script's folder; run, compare, render and batch
    # workers load it later from whatever working directory they have.
    from locoplan.robot.description import load_robot_description

    robot_yaml = Path(__file__).resolve().parents[1] / "robots" / "hector" / "robot.yaml"
    script = tmp_path / "scripts" / "s.yaml"
    script.parent.mkdir()
    rel = os.path.relpath(robot_yaml, script.parent)
    script.write_text(
        f"version: 1\nname: rel\nrobot: {rel}\n"
        "tasks:\n  - {action: stand, start: 0, duration: 1}\n"
    )
    loaded = load_scenario_file(script)
    assert Path(loaded.scenario.robot).is_absolute()
    monkeypatch.chdir(tmp_path)
    assert load_robot_description(loaded.scenario.robot).name == "hector"


def test_the_built_in_robot_h1_is_accepted(tmp_path: Path) -> None:
    # `robot: h1` names the robot directory robots/h1/ (a built-in name, kept as written).
    from locoplan.robot.description import load_robot_description

    script = tmp_path / "h1-stand.yaml"
    script.write_text(
        "version: 1\nname: h1-stand\nrobot: h1\n"
        "tasks:\n  - {action: stand, start: 0, duration: 1}\n"
    )
    loaded = load_scenario_file(script)
    assert loaded.scenario.robot == "h1" and loaded.robot_path is None
    assert load_robot_description(loaded.scenario.robot).name == "h1"
