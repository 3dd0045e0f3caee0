"""Parsing a task script's YAML into plain data with node positions.

Every failure becomes a `ScenarioError` with a 1-based line and column (1:1 when the problem
has no better place): YAML syntax errors, duplicate keys, YAML tags, values that cannot be
read, documents that are too large or nested too deeply.

The YAML is read with ruamel.yaml's round-trip loader, whose mappings and sequences remember
the line and column of every key and item. The result is converted to plain Python data
(dict, list, str, int, float, bool, None) next to a table of positions keyed by the path of
each node, so that a pydantic error `loc` can be mapped back to the file.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from ruamel.yaml import YAML
from ruamel.yaml.comments import CommentedMap, CommentedSeq, TaggedScalar
from ruamel.yaml.constructor import ConstructorError, RoundTripConstructor
from ruamel.yaml.error import MarkedYAMLError, YAMLError
from ruamel.yaml.events import (
    AliasEvent,
    CollectionEndEvent,
    CollectionStartEvent,
    MappingStartEvent,
    NodeEvent,
    ScalarEvent,
)
from ruamel.yaml.nodes import ScalarNode
from ruamel.yaml.reader import ReaderError

from locoplan.exceptions import ScenarioError, ScenarioIssue
from locoplan.scenario.source import MAX_BYTES, SourceText

__all__ = ["MAX_BYTES", "MAX_DEPTH", "MAX_NODES", "YamlDocument", "parse_yaml"]

# A task script is a few kilobytes; these bounds only keep hostile input cheap to reject
# (ruamel.yaml's pure-Python round-trip loader reads about 15,000 values per second here).
MAX_DEPTH = 32
# Nodes after expanding aliases (`&a` / `*a`), so that an alias bomb is rejected early.
MAX_NODES = 20_000

_YAML_TAG = "tag:yaml.org,2002:"
# Explicit tags that only restate what plain YAML already reads; every other tag is refused.
_ALLOWED_TAGS = frozenset(
    {"!"} | {_YAML_TAG + t for t in ("str", "int", "float", "bool", "null", "seq", "map")}
)

Position = tuple[int, int]
"""(line, column), both 1-based."""

Path_ = tuple[Hashable, ...]
"""Keys and indices from the document root to a node."""


@dataclass(frozen=True, slots=True)
class YamlDocument:
    """Plain data of one YAML document and the positions of its nodes.

    `positions[path]` is where the node at `path` starts (for a `null` mapping value: its key);
    `key_positions[path]` is where the key of the mapping entry at `path` starts.
    """

    data: Any
    positions: dict[Path_, Position]
    key_positions: dict[Path_, Position]

    def locate(self, loc: Sequence[Hashable]) -> Position:
        """Position of the deepest node along `loc` (a path of keys and indices).

        `loc` may end in `"[key]"` (the key itself rather than its value, as pydantic writes
        it), and may name keys that do not exist (a missing key): the walk stops at the
        deepest node that exists.
        """
        node = self.data
        path: Path_ = ()
        pos = self.positions.get((), (1, 1))
        for part in loc:
            if part == "[key]":
                return self.key_positions.get(path, pos)
            key = _find_key(node, part)
            if key is _MISSING:
                break
            path = (*path, key)
            node = node[key]
            pos = self.positions.get(path, pos)
        return pos


_MISSING = object()


def _find_key(node: Any, part: Hashable) -> Any:
    if isinstance(node, dict):
        if part in node:
            return part
        # pydantic writes keys that are not str or int as their str().
        for key in node:
            if not isinstance(key, str | int) and str(key) == part:
                return key
        return _MISSING
    if isinstance(node, list) and isinstance(part, int) and 0 <= part < len(node):
        return part
    return _MISSING


class _Constructor(RoundTripConstructor):
    """Round-trip constructor whose value errors (an integer of 5000 digits, the date
    2001-02-30, `!!float abc`) carry the position of the offending node."""

    def construct_object(self, node: Any, deep: bool = False) -> Any:
        try:
            return super().construct_object(node, deep=deep)
        except YAMLError:
            raise
        except (ValueError, OverflowError, TypeError, ArithmeticError) as exc:
            if isinstance(node, ScalarNode) and len(node.value) > 100:
                problem = f"value too long to read ({len(node.value)} characters)"
            else:
                problem = f"cannot read this value: {exc}"
            raise ConstructorError(problem=problem, problem_mark=node.start_mark) from exc


def _new_yaml() -> YAML:
    yaml = YAML(typ="rt", pure=True)
    yaml.Constructor = _Constructor
    return yaml


def parse_yaml(source: SourceText) -> YamlDocument:
    """Parse one YAML document into plain data with positions; raise ScenarioError on
    syntax errors, duplicate keys, tags, and documents too large or too deep."""
    yaml = _new_yaml()
    label = source.label
    try:
        issues = _scan_events(yaml, yaml.parse(source.text), label)
        if issues:
            raise ScenarioError(issues)
        raw = _new_yaml().load(source.text)
    except MarkedYAMLError as exc:
        raise ScenarioError([_issue_from_marked(label, exc)]) from None
    except ReaderError as exc:
        line, column = _position_of_index(source.text, exc.position)
        what = f"#x{exc.character:04x}" if isinstance(exc.character, int) else repr(exc.character)
        message = f"character {what} is not allowed in YAML ({exc.reason})"
        raise ScenarioError([ScenarioIssue(label, line, column, message)]) from None
    except YAMLError as exc:
        raise ScenarioError([ScenarioIssue(label, 1, 1, f"invalid YAML: {exc}")]) from None
    except RecursionError:
        # Not expected after the depth check; kept so that no input can escape as a crash.
        message = f"document nested too deeply (more than {MAX_DEPTH} levels)"
        raise ScenarioError([ScenarioIssue(label, 1, 1, message)]) from None
    positions: dict[Path_, Position] = {}
    key_positions: dict[Path_, Position] = {}
    root_pos = _lc_position(raw)
    data = _to_plain(raw, (), root_pos, positions, key_positions)
    return YamlDocument(data, positions, key_positions)


def _issue_from_marked(label: str, exc: MarkedYAMLError) -> ScenarioIssue:
    mark = exc.problem_mark or exc.context_mark
    line, column = (mark.line + 1, mark.column + 1) if mark is not None else (1, 1)
    problem = " ".join(str(exc.problem or "").split())
    context = " ".join(str(exc.context or "").split())
    if type(exc).__name__ == "DuplicateKeyError":
        message = f"{problem}; each key may appear once in a mapping"
    elif isinstance(exc, ConstructorError) and not context:
        message = problem
    elif problem.startswith("but ") and context:
        message = f"invalid YAML: {context}, {problem}"
    else:
        message = f"invalid YAML: {problem or context}"
        if context and problem and exc.context_mark is not None:
            cm = exc.context_mark
            message += f" ({context} at line {cm.line + 1}, column {cm.column + 1})"
    return ScenarioIssue(label, line, column, message)


def _position_of_index(text: str, index: int) -> Position:
    index = max(0, min(index, len(text)))
    line = text.count("\n", 0, index) + 1
    column = index - (text.rfind("\n", 0, index) + 1) + 1
    return line, column


def _scan_events(yaml: YAML, events: Iterable[Any], label: str) -> list[ScenarioIssue]:
    """Check the event stream before building any tree (event parsing is not recursive):
    nesting depth, size after alias expansion, recursive aliases, tags, duplicate keys."""
    issues: list[ScenarioIssue] = []
    # One frame per open collection: [expanded size, anchor, is mapping, children seen, keys].
    stack: list[list[Any]] = []
    sizes: dict[str, int] = {}
    expanded = 0

    def issue(event: Any, message: str) -> ScenarioIssue:
        mark = event.start_mark
        return ScenarioIssue(label, mark.line + 1, mark.column + 1, message)

    for event in events:
        if isinstance(event, CollectionEndEvent):
            size, anchor = stack[-1][0], stack[-1][1]
            stack.pop()
            if anchor is not None:
                sizes[anchor] = size
            if stack:
                stack[-1][0] += size
            continue
        if not isinstance(event, NodeEvent):
            continue
        if isinstance(event, AliasEvent):
            if event.anchor not in sizes and any(f[1] == event.anchor for f in stack):
                return [issue(event, f"alias *{event.anchor} refers to a node that contains it")]
            n = sizes.get(event.anchor, 1)
        else:
            n = 1
            tag = getattr(event, "tag", None)
            tag = getattr(tag, "value", tag)  # ruamel may wrap tags in a Tag object
            if tag is not None and tag not in _ALLOWED_TAGS:
                shown = "!!" + tag.removeprefix(_YAML_TAG) if tag.startswith(_YAML_TAG) else tag
                issues.append(issue(event, f"YAML tag {shown} is not allowed in a task script"))
        expanded += n
        if expanded > MAX_NODES:
            return [issue(event, f"document too large (more than {MAX_NODES} values)")]
        if stack and stack[-1][2]:
            frame = stack[-1]
            if frame[3] % 2 == 0 and isinstance(event, ScalarEvent):
                key = _key_identity(yaml, event)
                first = frame[4].get(key)
                if first is not None:
                    issues.append(
                        issue(
                            event,
                            f"duplicate key {event.value!r} (first at line {first[0]}, "
                            f"column {first[1]}); each key may appear once in a mapping",
                        )
                    )
                else:
                    mark = event.start_mark
                    frame[4][key] = (mark.line + 1, mark.column + 1)
            frame[3] += 1
        if isinstance(event, CollectionStartEvent):
            if len(stack) >= MAX_DEPTH:
                return [issue(event, f"document nested too deeply (more than {MAX_DEPTH} levels)")]
            is_map = isinstance(event, MappingStartEvent)
            stack.append([n, event.anchor, is_map, 0, {}])
        else:
            if stack:
                stack[-1][0] += n
            if isinstance(event, ScalarEvent) and event.anchor is not None:
                sizes[event.anchor] = 1
    return issues


def _key_identity(yaml: YAML, event: ScalarEvent) -> tuple[str, str]:
    """What makes two scalar keys equal: `1` and `"1"` differ (int vs str), `a` and `'a'` not."""
    tag = event.tag
    tag = getattr(tag, "value", tag)
    if tag is None or tag == "!":
        implicit = event.implicit if tag is None else (False, True)
        tag = yaml.resolver.resolve(ScalarNode, event.value, implicit)
        tag = getattr(tag, "value", tag)
    return str(tag), event.value


def _lc_position(node: Any) -> Position:
    lc = getattr(node, "lc", None)
    if lc is not None and lc.line is not None:
        return lc.line + 1, lc.col + 1
    return 1, 1


def _to_plain(
    node: Any,
    path: Path_,
    pos: Position,
    positions: dict[Path_, Position],
    key_positions: dict[Path_, Position],
) -> Any:
    """Copy ruamel's round-trip data into plain Python types, recording positions."""
    positions[path] = pos
    if isinstance(node, CommentedMap):
        plain: dict[Any, Any] = {}
        for key, value in node.items():
            key_pos = _lc_get(node, "key", key, pos)
            value_pos = key_pos if value is None else _lc_get(node, "value", key, key_pos)
            pkey = _plain_key(key)
            key_positions[(*path, pkey)] = key_pos
            plain[pkey] = _to_plain(value, (*path, pkey), value_pos, positions, key_positions)
        return plain
    if isinstance(node, CommentedSeq):
        return [
            _to_plain(item, (*path, i), _lc_get(node, "item", i, pos), positions, key_positions)
            for i, item in enumerate(node)
        ]
    return _plain_scalar(node)


def _lc_get(node: Any, what: str, key: Any, default: Position) -> Position:
    try:
        line, col = getattr(node.lc, what)(key)
    except (KeyError, IndexError, TypeError, AttributeError):
        return default  # merged keys (`<<: *base`) have no position of their own
    if line is None or col is None:
        return default
    return int(line) + 1, int(col) + 1


def _plain_key(key: Any) -> Hashable:
    if isinstance(key, tuple):  # ruamel's CommentedKeySeq for `? [a, b]`
        return tuple(_plain_key(k) for k in key)
    value = _plain_scalar(key)
    return value if isinstance(value, Hashable) else repr(value)


def _plain_scalar(value: Any) -> Any:
    # ruamel's scalar types subclass the builtins (ScalarBoolean subclasses int, not bool).
    if type(value).__name__ == "ScalarBoolean":
        return bool(value)
    if isinstance(value, TaggedScalar):  # `!!str 7`; other tags were refused by the scan
        return str(value.value)
    for cls in (bool, int, float, str):
        if isinstance(value, cls):
            return cls(value)
    return value  # dates, sets: kept, so that validation names their type
