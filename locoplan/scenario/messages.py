"""Turning pydantic validation errors into short messages that say what is wrong and what is
allowed, each with the document path (`loc`) it belongs to.

A `loc` is a tuple of mapping keys and list indices from the document root, as pydantic
writes it but without the discriminator tag of a task (`("tasks", 2, "object")`, not
`("tasks", 2, "pick", "object")`); it may end in `"[key]"` to mean a mapping key itself
rather than its value. `locoplan.scenario.yaml_source.YamlDocument.locate` maps it to a line
and column.
"""

from __future__ import annotations

import datetime
import difflib
import re
from collections.abc import Hashable, Iterable
from dataclasses import dataclass
from typing import Any

from pydantic_core import ErrorDetails

from locoplan.scenario.introspect import allowed_keys, fixed_length, required_keys
from locoplan.scenario.model import ACTIONS, FieldValueError

Loc = tuple[Hashable, ...]


@dataclass(frozen=True, slots=True)
class LocatedIssue:
    """A problem found in a document, at the node `loc` (see the module docstring)."""

    loc: Loc
    message: str


# Units of numeric fields, for messages like "duration must be > 0 s, got 0".
_UNITS = {
    "start": "s",
    "duration": "s",
    "end": "s",
    "period": "s",
    "swing": "s",
    "dt": "s",
    "max_completion_time": "s",
    "mass": "kg",
    "size": "m",
    "position": "m",
    "distance": "m",
    "at": "m",
    "yaw": "deg",
    "angle": "deg",
    "max_yaw_difference": "deg",
    "speed": "m/s",
    "velocity": "m/s",
}
_OPERATORS = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<"}
_OPERATORS["less_than_equal"] = "<="
_BOUND_KEYS = {"greater_than": "gt", "greater_than_equal": "ge", "less_than": "lt"}
_BOUND_KEYS["less_than_equal"] = "le"


def show(value: Any) -> str:
    """A short, single-line rendering of a YAML value for messages: strings quoted (with
    control characters escaped), `true`/`false`/`null` as YAML writes them."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        if value.bit_length() > 100:  # str() of a huge int is slow, or refused past 4300 digits
            return f"an integer of about {int(value.bit_length() * 0.30103) + 1} digits"
        return str(value)
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, str):
        return repr(value) if len(value) <= 60 else repr(value[:57]) + "..."
    if isinstance(value, list | tuple):
        return f"a list of {len(value)} item{'s' if len(value) != 1 else ''}"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, datetime.date):
        return f"the date {value.isoformat()}"
    return f"a value of type {type(value).__name__}"


def suggest(word: Any, choices: Iterable[str]) -> str:
    """' (did you mean 'x'?)' when `word` is close to one of `choices`, else ''."""
    if not isinstance(word, str):
        return ""
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.7)
    return f" (did you mean {close[0]!r}?)" if close else ""


def join(names: Iterable[str]) -> str:
    return ", ".join(names)


def validation_issues(errors: Iterable[ErrorDetails]) -> list[LocatedIssue]:
    """One issue per pydantic error (of `Scenario.model_validate`), duplicates dropped."""
    issues: list[LocatedIssue] = []
    seen: set[tuple[Loc, str]] = set()
    for error in errors:
        issue = _translate(error)
        if (issue.loc, issue.message) not in seen:
            seen.add((issue.loc, issue.message))
            issues.append(issue)
    return issues


def _translate(error: ErrorDetails) -> LocatedIssue:
    raw_loc = tuple(error["loc"])
    loc, action = _strip_tag(raw_loc)
    kind = error["type"]
    value = error.get("input")
    ctx = error.get("ctx") or {}
    field = _field_name(loc)

    if kind == "union_tag_invalid" and isinstance(value, dict):
        got = value.get("action")
        if isinstance(got, str):
            message = f"unknown action {show(got)}; allowed: {join(ACTIONS)}"
            message += suggest(got, ACTIONS)
        else:
            message = f"expected an action name, got {show(got)}; allowed: {join(ACTIONS)}"
        return LocatedIssue((*loc, "action"), message)
    if kind == "union_tag_not_found":
        return LocatedIssue(loc, f"task has no 'action'; allowed actions: {join(ACTIONS)}")
    if kind == "extra_forbidden":
        parent = loc[:-1]
        allowed = allowed_keys(parent, action)
        key = loc[-1] if loc else None
        message = f"unknown key {show(key)} {_where(parent, action)}"
        if allowed:
            message += f"; allowed: {join(allowed)}{suggest(key, allowed)}"
        return LocatedIssue((*loc, "[key]"), message)
    if kind == "missing":
        parent = loc[:-1]
        required = required_keys(parent, action)
        message = f"missing key {show(field)} {_where(parent, action)}"
        if required:
            message += f"; required: {join(required)}"
        return LocatedIssue(loc, message)
    if kind == "invalid_key":
        return LocatedIssue((*loc, "[key]"), f"keys must be strings, got {show(value)}")
    if kind == "value_error":
        exc = ctx.get("error")
        message = str(exc) if exc is not None else error["msg"].removeprefix("Value error, ")
        if isinstance(exc, FieldValueError):
            return LocatedIssue((*loc, exc.field), message)
        return LocatedIssue(loc, message)
    return LocatedIssue(loc, _value_message(kind, loc, field, action, value, ctx, error["msg"]))


def _value_message(
    kind: str,
    loc: Loc,
    field: str,
    action: str | None,
    value: Any,
    ctx: dict[str, Any],
    fallback: str,
) -> str:
    got = show(value)
    if loc and loc[-1] == "[key]":
        return f"names must be strings, got {got}; quote the name"
    if kind == "float_type":
        hint = "; write numbers without quotes" if _looks_numeric(value) else ""
        return f"expected a number, got {got}{hint}"
    if kind == "int_type":
        return f"expected an integer, got {got}"
    if kind == "string_type":
        hint = "; quote it to make it text" if not isinstance(value, list | dict) else ""
        return f"expected a string, got {got}{hint}"
    if kind == "bool_type":
        return f"expected true or false, got {got}"
    if kind == "list_type":
        length = fixed_length(loc, action)
        what = f"a list of {length} numbers" if length else "a list"
        return f"expected {what}, got {got}"
    if kind in ("dict_type", "model_type", "model_attributes_type"):
        if len(loc) == 2 and loc[0] == "tasks":
            example = "{action: stand, start: 0, duration: 1}"
            return f"expected a task mapping such as {example}, got {got}"
        return f"expected a mapping, got {got}"
    if kind == "literal_error":
        allowed = [s.strip("'") for s in re.split(r", | or ", str(ctx.get("expected", "")))]
        return f"invalid {field} {got}; allowed: {join(allowed)}{suggest(value, allowed)}"
    if kind in _OPERATORS:
        bound = ctx.get(_BOUND_KEYS[kind])
        unit = _UNITS.get(field, "")
        subject = f"{field} values" if isinstance(loc[-1], int) else field
        bound_text = f"{bound:g}" if isinstance(bound, int | float) else str(bound)
        unit_text = f" {unit}" if unit else ""
        return f"{subject} must be {_OPERATORS[kind]} {bound_text}{unit_text}, got {got}"
    if kind == "finite_number":
        return f"{field} must be a finite number, got {got}"
    if kind in ("too_short", "too_long"):
        return _length_message(kind, loc, field, action, ctx)
    if kind == "string_too_short":
        return f"{field} must not be empty"
    if kind == "string_too_long":
        return f"{field} is too long ({len(value)} characters); at most {ctx.get('max_length')}"
    return f"{fallback}, got {got}"


def _length_message(
    kind: str, loc: Loc, field: str, action: str | None, ctx: dict[str, Any]
) -> str:
    actual = ctx.get("actual_length")
    fixed = fixed_length(loc, action)
    if fixed:
        return f"{field} needs {fixed} values, got {actual}"
    if field == "tasks":
        return "tasks must list at least one task"
    if kind == "too_short":
        return f"{field} needs at least {ctx.get('min_length')} item(s), got {actual}"
    return f"{field} takes at most {ctx.get('max_length')} item(s), got {actual}"


def _looks_numeric(value: Any) -> bool:
    if not isinstance(value, str):
        return False
    try:
        float(value)
    except ValueError:
        return False
    return True


def _strip_tag(loc: Loc) -> tuple[Loc, str | None]:
    """Drop the discriminator tag pydantic puts after a task's index; return it too."""
    if len(loc) >= 3 and loc[0] == "tasks" and isinstance(loc[1], int) and loc[2] in ACTIONS:
        return (*loc[:2], *loc[3:]), str(loc[2])
    return loc, None


def _field_name(loc: Loc) -> str:
    for part in reversed(loc):
        if isinstance(part, str) and part != "[key]":
            return part
    return "value"


def _where(parent: Loc, action: str | None) -> str:
    if not parent:
        return "at the top level"
    if len(parent) == 2 and parent[0] == "tasks" and action:
        return f"in a {action} task"
    if len(parent) == 2 and parent[0] in ("objects", "fixtures"):
        return f"in {str(parent[0])[:-1]} {show(parent[1])}"
    return f"in {show(parent[-1])}"
