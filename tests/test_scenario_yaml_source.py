"""locoplan.scenario.yaml_source: YAML -> plain data with positions, and its limits."""

from __future__ import annotations

import pytest

from locoplan.exceptions import ScenarioError
from locoplan.scenario.source import SourceText
from locoplan.scenario.yaml_source import MAX_DEPTH, MAX_NODES, parse_yaml


def parse(text: str):
    return parse_yaml(SourceText("y.yaml", None, text))


def messages(text: str) -> list[str]:
    with pytest.raises(ScenarioError) as info:
        parse(text)
    return [str(i) for i in info.value.issues]


def test_plain_types_come_out() -> None:
    doc = parse("a: &t true\nb: *t\nc: 0x10\nd: 1_000\ne: 1.5\nf: !!str 7\ng: ~\nh: [x, 'y']\n")
    assert doc.data == {
        "a": True, "b": True, "c": 16, "d": 1000, "e": 1.5, "f": "7", "g": None, "h": ["x", "y"],
    }  # fmt: skip
    assert type(doc.data["a"]) is bool and type(doc.data["c"]) is int
    assert type(doc.data["e"]) is float and type(doc.data["h"][1]) is str


def test_positions_of_values_keys_and_items() -> None:
    text = "top:\n  inner: {k: 5, l: [1, two]}\nseq:\n  - a\n  -\n    m: 1\nempty:\n"
    doc = parse(text)
    assert doc.locate(()) == (1, 1)
    assert doc.locate(("top",)) == (2, 3)  # a block mapping starts at its first key
    assert doc.locate(("top", "inner", "k")) == (2, 14)
    assert doc.locate(("top", "inner", "l", 1)) == (2, 24)
    assert doc.locate(("top", "inner", "k", "[key]")) == (2, 11)
    assert doc.locate(("seq", 1, "m")) == (6, 8)
    assert doc.locate(("seq", 1)) == (6, 5)
    assert doc.locate(("empty",)) == (7, 1)  # a null value points at its key
    # Missing keys and indices stop at the deepest node that exists.
    assert doc.locate(("top", "inner", "missing", "deeper")) == (2, 10)
    assert doc.locate(("seq", 7)) == (4, 3)


def test_merge_keys_fall_back_to_the_merging_mapping() -> None:
    doc = parse("base: &b {x: 1}\nuse:\n  <<: *b\n  y: 2\n")
    assert doc.data["use"] == {"y": 2, "x": 1}
    assert doc.locate(("use", "y")) == (4, 6)
    assert doc.locate(("use", "x")) == (3, 3)


def test_syntax_errors_carry_the_problem_position() -> None:
    assert messages("a: [1, 2\nb: 3\n") == [
        "y.yaml:2:2: invalid YAML: expected ',' or ']', but got ':' "
        "(while parsing a flow sequence at line 1, column 4)"
    ]
    assert messages("a: *missing\n") == [
        "y.yaml:1:4: invalid YAML: found undefined alias 'missing'"
    ]
    assert messages("a: 'unterminated\n")[0].startswith("y.yaml:2:1: invalid YAML:")


def test_all_duplicate_keys_are_reported_with_both_positions() -> None:
    assert messages("a: 1\nb: {x: 1, x: 2}\na: 3\n'1': s\n1: i\n") == [
        "y.yaml:2:11: duplicate key 'x' (first at line 2, column 5); "
        "each key may appear once in a mapping",
        "y.yaml:3:1: duplicate key 'a' (first at line 1, column 1); "
        "each key may appear once in a mapping",
    ]  # '1' (a string) and 1 (an integer) are different keys


def test_depth_limit_for_flow_and_block_nesting() -> None:
    ok = "[" * (MAX_DEPTH - 1) + "]" * (MAX_DEPTH - 1)
    assert parse(f"a: {ok}\n").data is not None
    deep = "[" * (MAX_DEPTH + 5) + "]" * (MAX_DEPTH + 5)
    assert messages(f"a: {deep}\n") == [
        f"y.yaml:1:{3 + MAX_DEPTH}: document nested too deeply (more than {MAX_DEPTH} levels)"
    ]
    block = "".join("  " * i + "k:\n" for i in range(3000))  # far past Python's recursion limit
    assert "document nested too deeply" in messages(block)[0]


def test_alias_expansion_is_counted() -> None:
    layers = ["a0: &a0 [0, 0, 0, 0, 0, 0, 0, 0, 0, 0]"]
    for i in range(1, 6):
        layers.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]")
    [message] = messages("\n".join(layers) + "\n")
    assert message.endswith(f"document too large (more than {MAX_NODES} values)")
    assert messages("a: &x [1, *x]\n") == [
        "y.yaml:1:11: alias *x refers to a node that contains it"
    ]


def test_tags_are_refused_except_plain_core_ones() -> None:
    assert parse("a: !!int 3\nb: !!float 1\nc: ! text\n").data == {"a": 3, "b": 1.0, "c": "text"}
    assert messages("a: !!python/name:os.system x\nb: !local {x: 1}\n") == [
        "y.yaml:1:4: YAML tag !!python/name:os.system is not allowed in a task script",
        "y.yaml:2:4: YAML tag !local is not allowed in a task script",
    ]


def test_unreadable_values_carry_their_position() -> None:
    assert messages("a: 1\nb: 2001-02-30\n") == [
        "y.yaml:2:4: cannot read this value: day is out of range for month"
    ]
    assert messages("a: " + "1" * 5000 + "\n") == [
        "y.yaml:1:4: value too long to read (5000 characters)"
    ]


def test_control_characters_are_refused_at_their_position() -> None:
    assert messages("a: 1\nb: x\x1by\n") == [
        "y.yaml:2:5: character #x001b is not allowed in YAML (special characters are not allowed)"
    ]


def test_empty_documents_give_none() -> None:
    assert parse("").data is None
    assert parse("# just a comment\n").data is None
    assert parse("---\n...\n").data is None
