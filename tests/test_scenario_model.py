"""locoplan.scenario.model: strict types and the cross-field rules of single models."""

from __future__ import annotations

from typing import Any

import pytest
from pydantic import ValidationError

from locoplan.scenario import DropTask, GaitSettings, ObjectSpec, Scenario
from locoplan.scenario.model import FieldValueError


def errors(model: Any, data: dict[str, Any]) -> list[dict[str, Any]]:
    with pytest.raises(ValidationError) as info:
        model.model_validate(data)
    return [dict(e) for e in info.value.errors(include_url=False)]


def test_numbers_must_be_numbers_but_integers_are_floats() -> None:
    assert GaitSettings.model_validate({"period": 1, "swing": 0.5}).period == 1.0
    for bad in ("0.4", True, None):
        [e] = errors(GaitSettings, {"period": bad})
        assert e["type"] == "float_type"


def test_version_must_be_the_integer_one() -> None:
    base = {"name": "v", "tasks": [{"action": "stand", "start": 0, "duration": 1}]}
    assert Scenario.model_validate({**base, "version": 1}).version == 1
    for bad in (True, 1.0, "1", 2):
        assert errors(Scenario, {**base, "version": bad})[0]["loc"] == ("version",)


def test_cross_field_rules_name_their_field() -> None:
    [e] = errors(GaitSettings, {"period": 0.4, "swing": 0.25})
    assert isinstance(e["ctx"]["error"], FieldValueError) and e["ctx"]["error"].field == "swing"
    [e] = errors(ObjectSpec, {"shape": "sphere", "size": [1, 2], "mass": 1, "position": [0, 0, 0]})
    assert e["ctx"]["error"].field == "size"
    drop = {"action": "drop", "object": "b", "start": 0, "duration": 1}
    [e] = errors(DropTask, {**drop, "onto": "t", "at": [0, 0, 0]})
    assert e["ctx"]["error"].field == "at"
    [e] = errors(DropTask, drop)
    assert not isinstance(e["ctx"]["error"], FieldValueError)  # neither target: the task


def test_end_time_defaults_to_last_task_end_plus_settle() -> None:
    s = Scenario.model_validate(
        {
            "version": 1,
            "name": "e",
            "tasks": [
                {"action": "stand", "start": 0, "duration": 2},
                {"action": "turn", "angle": 90, "start": 1, "duration": 0.5},
            ],
        }
    )
    assert s.last_task_end == 2.0
    assert s.end_time == 2.0 + Scenario.SETTLE_TIME
    assert s.model_copy(update={"end": 5.0}).end_time == 5.0
