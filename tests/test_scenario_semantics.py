"""locoplan.scenario.semantics.check_semantics, on models built in Python (no YAML).

The file-level behaviour (positions, the CLI) is covered by tests/test_scenario_cli.py with
the fixtures in tests/data/scenarios/bad/.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from locoplan.scenario import FixtureSpec, Scenario, check_semantics
from locoplan.scenario.semantics import TIME_EPS

OBJECTS = {
    "box": {"shape": "box", "size": [0.2, 0.2, 0.2], "mass": 2.0, "position": [0, 0.5, 0.7]},
    "ball": {"shape": "sphere", "size": [0.1], "mass": 0.5, "position": [0.3, 0.5, 0.7]},
}
FIXTURES = {
    "table": {"kind": "table", "position": [0, 0.5, 0], "size": [0.5, 0.4, 0.6]},
    "belt": {"kind": "conveyor", "position": [0.6, 0, 0], "size": [1.2, 0.35, 0.5]},
}


def scenario(*tasks: dict[str, Any], **extra: Any) -> Scenario:
    data = {"version": 1, "name": "t", "objects": OBJECTS, "fixtures": FIXTURES}
    data.update(extra)
    data["tasks"] = list(tasks)
    return Scenario.model_validate(data)


def pick(obj: str, start: float, duration: float = 1.0) -> dict[str, Any]:
    return {"action": "pick", "object": obj, "start": start, "duration": duration}


def drop(obj: str, start: float, duration: float = 1.0, onto: str = "table") -> dict[str, Any]:
    return {"action": "drop", "object": obj, "onto": onto, "start": start, "duration": duration}


def throw(obj: str, start: float, duration: float = 0.5) -> dict[str, Any]:
    return {
        "action": "throw",
        "object": obj,
        "velocity": [1, 0, 1],
        "start": start,
        "duration": duration,
    }


def walk(start: float, duration: float) -> dict[str, Any]:
    return {"action": "walk", "distance": [1, 0], "start": start, "duration": duration}


def turn(start: float, duration: float) -> dict[str, Any]:
    return {"action": "turn", "angle": 90, "start": start, "duration": duration}


def step(start: float, duration: float) -> dict[str, Any]:
    return {"action": "step", "start": start, "duration": duration}


def stand(start: float, duration: float) -> dict[str, Any]:
    return {"action": "stand", "start": start, "duration": duration}


def issues(s: Scenario, base_dir: Path | None = None) -> list[tuple[tuple[Any, ...], str]]:
    return sorted(((i.loc, i.message) for i in check_semantics(s, base_dir=base_dir)), key=str)


def test_valid_pick_drop_repick_throw_has_no_issue() -> None:
    s = scenario(pick("box", 0), drop("box", 1), pick("box", 2), throw("box", 3))
    assert issues(s) == []


def test_drop_exactly_at_pick_end_is_fine_even_with_decimal_rounding() -> None:
    # 0.1 + 0.2 = 0.30000000000000004 > 0.3: a drop "at" the pick end must still count.
    assert 0.1 + 0.2 > 0.3
    s = scenario(pick("box", 0.1, 0.2), drop("box", 0.3), walk(0.1, 0.2), turn(0.3, 1.0))
    assert issues(s) == []


def test_order_in_the_file_does_not_matter_only_time() -> None:
    s = scenario(drop("box", 2), pick("box", 0))
    assert issues(s) == []


def test_drop_without_pick() -> None:
    [(loc, message)] = issues(scenario(drop("box", 1)))
    assert loc == ("tasks", 0)
    assert message.startswith("cannot drop 'box' at 1 s: it is not held then; no pick")


def test_drop_before_the_pick_ends() -> None:
    [(loc, message)] = issues(scenario(pick("box", 1), drop("box", 1.5)))
    assert loc == ("tasks", 1)
    assert "its pick (task 1) ends only at 2 s; a drop must start at or after the end" in message


def test_drop_just_inside_the_tolerance_is_still_fine_but_not_beyond() -> None:
    # TIME_EPS absorbs rounding only: 1e-6 s early is an error.
    assert issues(scenario(pick("box", 0), drop("box", 1 - TIME_EPS / 2))) == []
    assert len(issues(scenario(pick("box", 0), drop("box", 1 - 1e-6)))) == 1


def test_second_drop_or_throw_after_release() -> None:
    [(loc, message)] = issues(scenario(pick("box", 0), drop("box", 1), throw("box", 3)))
    assert loc == ("tasks", 2)
    assert "task 2 already released it (drop at 1 s)" in message


def test_pick_of_held_object_and_of_object_still_being_picked() -> None:
    [(loc, message)] = issues(scenario(pick("box", 0), pick("box", 2)))
    assert loc == ("tasks", 1) and "it is already held (picked by task 1, 0..1 s)" in message
    found = issues(scenario(pick("box", 0, 2.0), pick("box", 1)))
    # Reported as a holding error only, not a second time as a manipulation overlap.
    assert len(found) == 1 and "it is still being picked" in found[0][1]


def test_two_objects_held_at_once_is_allowed() -> None:
    s = scenario(pick("box", 0), pick("ball", 1), drop("box", 2), throw("ball", 3))
    assert issues(s) == []


@pytest.mark.parametrize(
    ("first", "second"),
    [(walk(0, 2), turn(1, 2)), (step(0, 5), walk(1, 1)), (turn(1, 1), turn(1, 1))],
)
def test_overlapping_locomotion(first: dict[str, Any], second: dict[str, Any]) -> None:
    [(loc, message)] = issues(scenario(first, second))
    assert loc == ("tasks", 1)
    assert "two locomotion tasks (step, walk, turn) cannot run at the same time" in message


def test_touching_locomotion_and_stand_overlapping_anything_are_fine() -> None:
    assert issues(scenario(walk(0, 1), turn(1, 1), step(2, 1), stand(0, 3))) == []


def test_locomotion_overlapping_manipulation_is_the_point_of_the_dynamic_strategy() -> None:
    assert issues(scenario(turn(0, 1.5), pick("box", 1), turn(2.2, 1.5), drop("box", 3.2))) == []


def test_overlapping_manipulation_of_different_objects() -> None:
    [(loc, message)] = issues(scenario(pick("box", 0), pick("ball", 0.5)))
    assert loc == ("tasks", 1)
    assert "manipulation tasks (pick, drop, throw) cannot overlap in time" in message
    assert "a locoplan rule in addition to format v1" in message


def test_task_after_end() -> None:
    found = issues(scenario(stand(0, 2), walk(2, 3), end=4.0))
    assert found == [
        (("tasks", 1), "walk ends at 5 s, after end: 4 s; shorten or move the task, or raise 'end'")
    ]
    assert issues(scenario(stand(0, 2), walk(2, 2), end=4.0)) == []


def test_unknown_names() -> None:
    s = scenario(
        pick("crate", 0), drop("box", 1, onto="shelf"), expect={"placed": {"bal": "tabel"}}
    )
    by_loc = dict(issues(s))
    assert by_loc[("tasks", 0, "object")] == ("unknown object 'crate'; declared objects: box, ball")
    assert by_loc[("tasks", 1, "onto")] == "unknown fixture 'shelf'; declared fixtures: table, belt"
    assert by_loc[("expect", "placed", "bal", "[key]")].startswith(
        "unknown object 'bal' in expect.placed; declared objects: box, ball (did you mean 'ball'?)"
    )
    assert by_loc[("expect", "placed", "bal")].endswith("(did you mean 'table'?)")
    # The unknown object is not also reported as "not held" (no follow-on noise).
    assert len(by_loc) == 4 + 1  # the box drop itself is not held either: a real error


def test_no_objects_declared() -> None:
    s = Scenario.model_validate({"version": 1, "name": "t", "tasks": [pick("box", 0)]})
    [(_, message)] = issues(s)
    assert message == "unknown object 'box'; no objects are declared (add them under 'objects:')"


def test_drop_onto_a_fixture_without_a_top() -> None:
    """Every kind of format v1 has a top; a kind added later without one is refused."""
    s = scenario(pick("box", 0), drop("box", 1, onto="wall"))
    wall = FixtureSpec.model_construct(
        kind="wall", position=[0.0, 0.0, 0.0], size=[1.0, 0.1, 2.0], yaw=0.0, speed=None
    )
    s = s.model_copy(update={"fixtures": {**s.fixtures, "wall": wall}})
    [(loc, message)] = issues(s)
    assert loc == ("tasks", 1, "onto")
    assert message == (
        "cannot drop onto 'wall', a wall: allowed fixture kinds: table, platform, conveyor"
    )


def test_robot_names_and_paths(tmp_path: Path) -> None:
    s = scenario(stand(0, 1), robot="atlas")
    [(loc, message)] = issues(s)
    assert loc == ("robot",) and message.startswith("unknown robot 'atlas'; allowed: hector")
    assert issues(scenario(stand(0, 1), robot="hectr"))[0][1].endswith("(did you mean 'hector'?)")
    assert issues(scenario(stand(0, 1), robot="h1")) == []
    (tmp_path / "robots").mkdir()
    (tmp_path / "robots" / "mine.yaml").write_text("name: mine\n")
    assert issues(scenario(stand(0, 1), robot="robots/mine.yaml"), base_dir=tmp_path) == []
    [(loc, message)] = issues(scenario(stand(0, 1), robot="robots/other.xml"), base_dir=tmp_path)
    assert loc == ("robot",)
    assert message.startswith("robot file 'robots/other.xml' not found")
    absolute = str(tmp_path / "robots" / "mine.yaml")
    assert issues(scenario(stand(0, 1), robot=absolute)) == []
    # A directory is not a robot file; a name with a NUL byte must not crash.
    (tmp_path / "dir.xml").mkdir()
    assert len(issues(scenario(stand(0, 1), robot="dir.xml"), base_dir=tmp_path)) == 1
    assert len(issues(scenario(stand(0, 1), robot="a\x00.xml"), base_dir=tmp_path)) == 1
