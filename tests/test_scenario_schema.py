"""locoplan.scenario.schema.scenario_json_schema.

No JSON Schema validator is installed, so a small checker below covers the keywords pydantic
emits (enough to show that the good fixtures conform and that typos do not).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from ruamel.yaml import YAML

from locoplan.scenario import ACTIONS, scenario_json_schema

DATA = Path(__file__).parent / "data" / "scenarios"
GOOD = sorted((DATA / "good").glob("*.yaml"))
HANDLED = {
    "$schema", "$defs", "$ref", "title", "description", "default", "type", "properties",
    "required", "additionalProperties", "items", "minItems", "maxItems", "anyOf", "oneOf",
    "discriminator", "const", "enum", "minimum", "maximum", "exclusiveMinimum",
    "exclusiveMaximum", "minLength", "maxLength",
}  # fmt: skip
_TYPES = {
    "object": dict,
    "array": list,
    "string": str,
    "boolean": bool,
    "null": type(None),
}


def conforms(value: Any, schema: dict[str, Any], root: dict[str, Any]) -> bool:
    unknown = set(schema) - HANDLED
    assert not unknown, f"checker does not know {unknown}"
    if "$ref" in schema:
        name = schema["$ref"].removeprefix("#/$defs/")
        return conforms(value, root["$defs"][name], root)
    if "anyOf" in schema and not any(conforms(value, s, root) for s in schema["anyOf"]):
        return False
    if "oneOf" in schema and sum(conforms(value, s, root) for s in schema["oneOf"]) != 1:
        return False
    if "const" in schema and value != schema["const"]:
        return False
    if "enum" in schema and value not in schema["enum"]:
        return False
    kind = schema.get("type")
    if kind == "number":
        if isinstance(value, bool) or not isinstance(value, int | float):
            return False
    elif kind == "integer":
        if isinstance(value, bool) or not isinstance(value, int):
            return False
    elif kind is not None and not isinstance(value, _TYPES[kind]):
        return False
    if isinstance(value, int | float) and not isinstance(value, bool):
        if "minimum" in schema and value < schema["minimum"]:
            return False
        if "maximum" in schema and value > schema["maximum"]:
            return False
        if "exclusiveMinimum" in schema and value <= schema["exclusiveMinimum"]:
            return False
        if "exclusiveMaximum" in schema and value >= schema["exclusiveMaximum"]:
            return False
    if isinstance(value, str) and not (
        schema.get("minLength", 0) <= len(value) <= schema.get("maxLength", 1e9)
    ):
        return False
    if isinstance(value, list):
        if len(value) < schema.get("minItems", 0) or len(value) > schema.get("maxItems", 1e9):
            return False
        if "items" in schema and not all(conforms(v, schema["items"], root) for v in value):
            return False
    if isinstance(value, dict):
        if not all(k in value for k in schema.get("required", [])):
            return False
        props = schema.get("properties", {})
        extra = schema.get("additionalProperties", True)
        for k, v in value.items():
            if k in props:
                if not conforms(v, props[k], root):
                    return False
            elif extra is False or (isinstance(extra, dict) and not conforms(v, extra, root)):
                return False
    return True


def load_plain(path: Path) -> Any:
    return json.loads(json.dumps(YAML(typ="safe", pure=True).load(path)))


def test_schema_is_draft_2020_12_with_title_and_description() -> None:
    schema = scenario_json_schema()
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert schema["title"] == "locoplan task script, version 1"
    assert "degrees" in schema["description"]
    assert schema["type"] == "object" and schema["additionalProperties"] is False
    assert set(schema["required"]) == {"version", "name", "tasks"}
    json.dumps(schema)  # serialisable as is


def test_every_ref_resolves_and_every_action_has_a_branch() -> None:
    schema = scenario_json_schema()
    text = json.dumps(schema)
    for name in schema["$defs"]:
        assert f'"#/$defs/{name}"' in text or name == "Scenario"
    refs = [part.split('"')[0] for part in text.split('"$ref": "#/$defs/')[1:]]
    assert all(ref in schema["$defs"] for ref in refs)
    branches = schema["properties"]["tasks"]["items"]["oneOf"]
    consts = {schema["$defs"][b["$ref"].removeprefix("#/$defs/")]["properties"]["action"]["const"]
              for b in branches}  # fmt: skip
    assert consts == set(ACTIONS)


def test_descriptions_carry_units() -> None:
    defs = scenario_json_schema()["$defs"]
    assert "kg" in defs["ObjectSpec"]["properties"]["mass"]["description"]
    assert "degrees" in defs["TurnTask"]["properties"]["angle"]["description"]


@pytest.mark.parametrize("path", GOOD, ids=lambda p: p.name)
def test_good_fixtures_conform(path: Path) -> None:
    schema = scenario_json_schema()
    assert conforms(load_plain(path), schema, schema)


def test_typos_and_wrong_types_do_not_conform() -> None:
    schema = scenario_json_schema()
    good = load_plain(DATA / "good" / "format-example.yaml")
    assert conforms(good, schema, schema)
    for mutate in (
        lambda d: d["tasks"][0].update(angel=1),
        lambda d: d["tasks"][0].update(action="jump"),
        lambda d: d["objects"]["package"].update(mass="heavy"),
        lambda d: d.update(strategy="fast"),
        lambda d: d.pop("name"),
        lambda d: d["tasks"][1].update(duration=0),
    ):
        bad = json.loads(json.dumps(good))
        mutate(bad)
        assert not conforms(bad, schema, schema)
