"""Property test: whatever a task script contains, loading either succeeds or raises a
ScenarioError whose issues all have a position (line, column >= 1) and a message, and
`locoplan validate` exits with 0 or 2 and prints something, never a traceback.

Valid documents (the good fixtures) are mutated structurally (keys dropped, values replaced
by wrong types, huge numbers or random unicode, tasks shuffled) and textually (truncation,
garbage bytes, deep nesting, random characters). About 200 examples in all, so that the
module runs in seconds.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from ruamel.yaml import YAML
from typer.testing import CliRunner

from locoplan.cli import EXIT_BAD_INPUT, EXIT_OK, app
from locoplan.exceptions import ScenarioError
from locoplan.scenario import Scenario, load_scenario

GOOD = sorted((Path(__file__).parent / "data" / "scenarios" / "good").glob("*.yaml"))
TEXTS = [p.read_bytes() for p in GOOD]
PLAIN = [YAML(typ="safe", pure=True).load(t) for t in TEXTS]

# deadline=None: the first examples pay for imports and ruamel's warm-up.
SETTINGS = settings(
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


def assert_loads_or_reports(text: bytes | str) -> None:
    try:
        result = load_scenario("fuzz.yaml", text)
    except ScenarioError as exc:
        assert exc.issues
        for issue in exc.issues:
            assert issue.path == "fuzz.yaml"
            assert issue.line >= 1 and issue.column >= 1, issue
            assert issue.message and "\n" not in issue.message, issue
    else:
        assert isinstance(result, Scenario)


def dump(data: Any) -> str:
    stream = io.StringIO()
    YAML(typ="safe", pure=True).dump(data, stream)
    return stream.getvalue()


def paths(node: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    found = [prefix]
    if isinstance(node, dict):
        for key, value in node.items():
            found += paths(value, (*prefix, key))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            found += paths(value, (*prefix, i))
    return found


def copy(data: Any) -> Any:
    if isinstance(data, dict):
        return {k: copy(v) for k, v in data.items()}
    if isinstance(data, list):
        return [copy(v) for v in data]
    return data


huge_numbers = st.one_of(
    st.integers(min_value=10**20, max_value=10**400),
    st.integers(max_value=-(10**20)),
    st.sampled_from([1e308, -1e308, 1e-320, float("inf"), float("-inf"), float("nan")]),
)
random_values = st.recursive(
    st.one_of(
        st.none(),
        st.booleans(),
        st.integers(),
        st.floats(),
        st.text(max_size=20),
        huge_numbers,
    ),
    lambda inner: st.one_of(
        st.lists(inner, max_size=4),
        st.dictionaries(st.text(max_size=8), inner, max_size=4),
    ),
    max_leaves=10,
)


@st.composite
def structural_mutation(draw: st.DrawFn) -> str:
    data = copy(draw(st.sampled_from(PLAIN)))
    for _ in range(draw(st.integers(min_value=1, max_value=3))):
        all_paths = paths(data)
        path = draw(st.sampled_from(all_paths))
        kind = draw(st.sampled_from(["drop", "replace", "huge", "unicode", "shuffle", "key"]))
        if not path:
            if kind == "replace":
                data = draw(random_values)
            continue
        parent = data
        for part in path[:-1]:
            parent = parent[part]
        last = path[-1]
        if kind == "drop":
            del parent[last]
        elif kind == "replace":
            parent[last] = draw(random_values)
        elif kind == "huge":
            parent[last] = draw(huge_numbers)
        elif kind == "unicode":
            parent[last] = draw(st.text(min_size=0, max_size=30))
        elif kind == "shuffle" and isinstance(data, dict) and isinstance(data.get("tasks"), list):
            data["tasks"] = draw(st.permutations(data["tasks"]))
        elif kind == "key" and isinstance(parent, dict):
            parent[draw(st.text(max_size=10))] = parent.pop(last)
    return dump(data)


@st.composite
def text_mutation(draw: st.DrawFn) -> bytes:
    text = draw(st.sampled_from(TEXTS))
    kind = draw(st.sampled_from(["truncate", "garbage", "deep", "unicode", "splice"]))
    at = draw(st.integers(min_value=0, max_value=len(text)))
    if kind == "truncate":
        return text[:at]
    if kind == "garbage":
        return text[:at] + draw(st.binary(min_size=1, max_size=40)) + text[at:]
    if kind == "deep":
        depth = draw(st.integers(min_value=1, max_value=3000))
        opener = draw(st.sampled_from(["[", "{a: ", "- "]))
        if opener == "- ":
            nested = "".join("\n" + "  " * i + "- " for i in range(min(depth, 200))) + "x"
        else:
            nested = opener * depth + ("]" if opener == "[" else "}") * depth
        return text + f"\ndeep: {nested}\n".encode()
    if kind == "unicode":
        return text[:at] + draw(st.text(min_size=1, max_size=20)).encode("utf-8") + text[at:]
    other = draw(st.sampled_from(TEXTS))
    return text[:at] + other[draw(st.integers(min_value=0, max_value=len(other))) :]


@settings(SETTINGS, max_examples=80)
@given(structural_mutation())
def test_structural_mutations_load_or_report(text: str) -> None:
    assert_loads_or_reports(text)


@settings(SETTINGS, max_examples=80)
@given(text_mutation())
def test_text_mutations_load_or_report(text: bytes) -> None:
    assert_loads_or_reports(text)


@settings(SETTINGS, max_examples=40)
@given(st.one_of(structural_mutation().map(str.encode), text_mutation()))
def test_cli_exits_0_or_2_with_a_message(text: bytes) -> None:
    result = CliRunner().invoke(app, ["validate", "-"], input=text)
    assert result.exception is None or isinstance(result.exception, SystemExit)
    assert result.exit_code in (EXIT_OK, EXIT_BAD_INPUT)
    assert result.output.strip()
    assert "Traceback" not in result.output
    first = result.output.splitlines()[0]
    assert first.startswith("ok   <stdin> (") or first.startswith("<stdin>:")
