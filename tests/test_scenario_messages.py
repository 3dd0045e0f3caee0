"""locoplan.scenario.messages and .introspect: pydantic errors -> located messages."""

from __future__ import annotations

import datetime
from typing import Any

from pydantic import ValidationError

from locoplan.scenario import Scenario
from locoplan.scenario.introspect import allowed_keys, fixed_length, required_keys
from locoplan.scenario.messages import LocatedIssue, show, suggest, validation_issues


def located(data: dict[str, Any]) -> list[LocatedIssue]:
    try:
        Scenario.model_validate(data)
    except ValidationError as exc:
        return validation_issues(exc.errors(include_url=False))
    return []


BASE = {"version": 1, "name": "m", "tasks": [{"action": "stand", "start": 0, "duration": 1}]}


def test_show_renders_yaml_values_on_one_line() -> None:
    assert show(None) == "null" and show(True) == "true" and show(3) == "3"
    assert show(1.5) == "1.5" and show(float("inf")) == "inf"
    assert show("a\nb\x1b") == "'a\\nb\\x1b'"  # control characters never reach a terminal
    assert show("x" * 100) == repr("x" * 57) + "..."
    assert show([1]) == "a list of 1 item" and show({}) == "a mapping"
    assert show(10**5000) == "an integer of about 5001 digits"  # 10**5000 has 5001
    assert show(datetime.date(2020, 1, 2)) == "the date 2020-01-02"


def test_suggest() -> None:
    assert suggest("angel", ["angle", "start"]) == " (did you mean 'angle'?)"
    assert suggest("zzz", ["angle"]) == "" and suggest(3, ["angle"]) == ""


def test_task_discriminator_is_removed_from_loc() -> None:
    data = {**BASE, "tasks": [{"action": "pick", "start": 0, "duration": 1}]}
    [issue] = located(data)
    assert issue.loc == ("tasks", 0, "object")  # pydantic says ("tasks", 0, "pick", "object")
    assert issue.message == (
        "missing key 'object' in a pick task; required: action, start, duration, object"
    )


def test_unknown_action_points_at_the_action_value() -> None:
    [issue] = located({**BASE, "tasks": [{"action": "jump", "start": 0, "duration": 1}]})
    assert issue.loc == ("tasks", 0, "action")
    assert (
        issue.message
        == "unknown action 'jump'; allowed: stand, step, walk, turn, pick, drop, throw"
    )


def test_unknown_key_points_at_the_key() -> None:
    [issue] = located({**BASE, "mpc": {"dt": 0.03, "horizn": 20}})
    assert issue.loc == ("mpc", "horizn", "[key]")
    assert issue.message == (
        "unknown key 'horizn' in 'mpc'; allowed: dt, horizon (did you mean 'horizon'?)"
    )


def test_cross_field_rule_points_at_its_field() -> None:
    [issue] = located({**BASE, "gait": {"period": 0.4, "swing": 0.3}})
    assert issue.loc == ("gait", "swing")


def test_introspection() -> None:
    assert allowed_keys(("tasks", 0), "turn") == ["action", "start", "duration", "angle"]
    assert required_keys((), None) == ["version", "name", "tasks"]
    assert allowed_keys(("objects", "box"), None)[:2] == ["shape", "size"]
    assert fixed_length(("robot_start", "position"), None) == 2
    assert fixed_length(("tasks", 0, "at"), "drop") == 3  # `list | None` keeps its length
    assert fixed_length(("objects", "box", "size"), None) is None  # 1 or 3 by shape
    assert allowed_keys(("nowhere",), None) == []
