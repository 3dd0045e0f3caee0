"""Sweep grids: `--set` parsing, points written into the script and validated
(locoplan/batch/sweep.py). No simulation."""

from __future__ import annotations

from pathlib import Path

import pytest

from locoplan.batch.errors import SweepSpecError
from locoplan.batch.sweep import (
    build_points,
    format_value,
    parse_set,
    parse_values,
)
from locoplan.scenario import load_scenario

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


def test_ranges_include_the_stop_and_keep_integers() -> None:
    assert parse_values("s", "1:14:1") == tuple(range(1, 15))
    assert parse_values("s", "0:16:4") == (0, 4, 8, 12, 16)
    assert parse_values("s", "0:10:4") == (0, 4, 8)  # 12 would overshoot the stop
    assert parse_values("s", "5:1:-2") == (5, 3, 1)


def test_float_ranges_have_no_binary_noise() -> None:
    values = parse_values("s", "0.1:0.5:0.1")
    # 0.1 * 3 is 0.30000000000000004 in binary; the sweep writes the value the user meant.
    assert values == (0.1, 0.2, 0.3, 0.4, 0.5)
    assert [format_value(v) for v in values] == ["0.1", "0.2", "0.3", "0.4", "0.5"]


def test_lists_parse_yaml_like_scalars() -> None:
    assert parse_values("s", "0.6,0.8,1") == (0.6, 0.8, 1)
    assert parse_values("s", "true,False") == (True, False)
    assert parse_values("s", "left, right") == ("left", "right")


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("mass", "expected KEY=VALUES"),
        ("mass=", "expected KEY=VALUES"),
        ("a..b=1", "not a dotted key"),
        ("m=1:2", "START:STOP:STEP"),
        ("m=1:x:1", "three numbers"),
        ("m=1:5:0", "never gets from 1 to 5"),
        ("m=5:1:1", "never gets from 5 to 1"),
        ("m=0:1e9:1", r"values \(at most"),
        ("m=1,,2", "empty value"),
    ],
)
def test_bad_specs_say_what_is_wrong(spec: str, message: str) -> None:
    with pytest.raises(SweepSpecError, match=message) as info:
        parse_set(spec)
    assert info.value.spec == spec
    assert str(info.value).startswith(f"--set {spec}: ")


def test_points_are_the_script_with_values_written_in(tmp_path: Path) -> None:
    axes = [parse_set("objects.box.mass=6,2"), parse_set("tasks.1.start=0.6,0.5")]
    points = build_points(tmp_path / "lift.yaml", SCRIPT, axes)
    assert [p.values for p in points] == [(2, 0.5), (2, 0.6), (6, 0.5), (6, 0.6)]
    assert [p.index for p in points] == [0, 1, 2, 3]
    assert all(p.error is None and p.text is not None for p in points)
    text = points[3].text or ""
    # Comments and lines kept, so the validator's line numbers are those of the file.
    assert text.splitlines()[6].split() == ["mass:", "6", "#", "kg"]
    assert text.splitlines()[11] == "  - {action: stand, start: 0.0, duration: 0.5}"
    scenario = load_scenario("lift.yaml", text)
    assert scenario.objects["box"].mass == 6
    assert scenario.tasks[1].start == 0.6
    assert scenario.tasks[0].start == 0.0


def test_missing_mapping_keys_are_created(tmp_path: Path) -> None:
    points = build_points(tmp_path / "lift.yaml", SCRIPT, [parse_set("gait.period=0.3,0.4")])
    assert [load_scenario("x", p.text or "").gait.period for p in points] == [0.3, 0.4]


def test_invalid_points_name_key_value_and_line(tmp_path: Path) -> None:
    source = tmp_path / "lift.yaml"
    points = build_points(source, SCRIPT, [parse_set("objects.box.mass=-1,3")])
    bad, good = points
    assert good.error is None
    assert bad.text is None and bad.error is not None
    # mass is on line 7, its value in column 11 (1-based)
    assert bad.error.startswith(f"objects.box.mass=-1: invalid: {source}:7:11: ")


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("tasks.5.start=1", r"tasks.5: index out of range \(the list has 2 items"),
        ("tasks.start=1", "tasks.start: a list takes an index"),
        ("end.x=1", "end.x: the parent is not a mapping"),
    ],
)
def test_keys_that_cannot_be_set(tmp_path: Path, spec: str, message: str) -> None:
    with pytest.raises(SweepSpecError, match=message):
        build_points(tmp_path / "lift.yaml", SCRIPT, [parse_set(spec)])


def test_duplicate_keys_and_empty_grids_are_refused(tmp_path: Path) -> None:
    with pytest.raises(SweepSpecError, match="once"):
        build_points(tmp_path / "x.yaml", SCRIPT, [parse_set("end=2"), parse_set("end=3")])
    with pytest.raises(SweepSpecError, match="at least one"):
        build_points(tmp_path / "x.yaml", SCRIPT, [])
