"""JSON Schema of the task-script format, generated from the pydantic models.

For editors (YAML language servers read JSON Schema) and CI linters. The schema describes
structure and types; the semantic rules (`locoplan.scenario.semantics`) are not expressible
in it, so `locoplan validate` stays the authority.
"""

from __future__ import annotations

from typing import Any

from locoplan.scenario.model import Scenario

JSON_SCHEMA_DIALECT = "https://json-schema.org/draft/2020-12/schema"


def scenario_json_schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a task script, format version 1, as a dict."""
    generated = Scenario.model_json_schema(mode="validation")
    generated.pop("title", None)
    generated.pop("description", None)
    return {
        "$schema": JSON_SCHEMA_DIALECT,
        "title": "locoplan task script, version 1",
        "description": (
            "A humanoid loco-manipulation task script for locoplan: objects, fixtures and "
            "timed tasks (stand, step, walk, turn, pick, drop, throw). Lengths in m, masses "
            "in kg, times in s, angles in degrees. Semantic rules (objects held before a "
            "drop, no overlapping locomotion, tasks within 'end') are checked by "
            "'locoplan validate', not by this schema."
        ),
        **generated,
    }
