"""Tests of locoplan.log.jsonenc: strict JSON from numpy-laden payloads, schema inference."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from locoplan.log.jsonenc import encode_json, infer_schema, make_json_encoder, to_jsonable


def _strict_loads(data: bytes) -> Any:
    def reject(token: str) -> None:
        raise ValueError(f"non-standard JSON token {token}")

    return json.loads(data, parse_constant=reject)


def test_numpy_values_become_plain_json() -> None:
    payload = {
        "a": np.arange(6.0).reshape(2, 3),
        "i": np.int64(3),
        "f": np.float32(0.5),
        "b": np.bool_(True),
        "ints": np.array([1, 2], dtype=np.int32),
        "flags": np.array([True, False]),
        "t": (1, 2.5),
        "none": None,
    }
    assert _strict_loads(encode_json(payload)) == {
        "a": [[0.0, 1.0, 2.0], [3.0, 4.0, 5.0]],
        "i": 3,
        "f": 0.5,
        "b": True,
        "ints": [1, 2],
        "flags": [True, False],
        "t": [1, 2.5],
        "none": None,
    }


def test_non_finite_floats_become_null_and_strings_survive() -> None:
    payload = {
        "x": math.nan,
        "v": np.array([1.0, np.inf, -np.inf]),
        "msg": "NaN in the WBC, Infinity cost",
        "deep": [{"y": np.float64("nan")}],
    }
    assert _strict_loads(encode_json(payload)) == {
        "x": None,
        "v": [1.0, None, None],
        "msg": "NaN in the WBC, Infinity cost",
        "deep": [{"y": None}],
    }


def test_decimals_round_float_arrays_only() -> None:
    encode = make_json_encoder(2)
    assert _strict_loads(encode({"v": np.array([0.123456]), "s": 0.123456})) == {
        "v": [0.12],
        "s": 0.123456,
    }
    assert _strict_loads(encode({"v": np.array([0.126, math.nan])})) == {"v": [0.13, None]}


def test_unsupported_values_are_rejected() -> None:
    with pytest.raises(TypeError, match="object"):
        encode_json({"a": object()})
    with pytest.raises(TypeError, match="keys"):
        to_jsonable({1: 2.0})
    with pytest.raises(TypeError):
        to_jsonable(np.array(["a", "b"]))


finite_or_not = st.floats(allow_nan=True, allow_infinity=True)
leaves = st.none() | st.booleans() | st.integers(-(2**53), 2**53) | finite_or_not | st.text()
payloads = st.dictionaries(
    st.text(),
    st.recursive(
        leaves,
        lambda children: (
            st.lists(children, max_size=4) | st.dictionaries(st.text(), children, max_size=4)
        ),
        max_leaves=20,
    ),
    max_size=6,
)


@given(payloads)
def test_encoding_round_trips_to_jsonable(payload: dict[str, Any]) -> None:
    # Exact equality: JSON prints the shortest repr, which parses back to the same double.
    assert _strict_loads(encode_json(payload)) == to_jsonable(payload)


def test_schema_inference() -> None:
    schema = infer_schema(
        {
            "n": 1,
            "x": 0.5,
            "ok": True,
            "s": "a",
            "m": np.zeros((2, 3)),
            "flags": np.zeros(4, dtype=bool),
            "list": [{"a": 1.0}],
            "empty": [],
            "none": None,
            "obj": {"y": np.float32(1.0)},
        },
        "locoplan.test",
    )
    assert schema["title"] == "locoplan.test"
    assert schema["type"] == "object"
    p = schema["properties"]
    assert p["n"] == p["x"] == {"type": "number"}  # an int field may later hold a float
    assert p["ok"] == {"type": "boolean"}
    assert p["s"] == {"type": "string"}
    assert p["m"] == {"type": "array", "items": {"type": "array", "items": {"type": "number"}}}
    assert p["flags"] == {"type": "array", "items": {"type": "boolean"}}
    assert p["list"]["items"]["properties"]["a"] == {"type": "number"}
    assert p["empty"] == {"type": "array", "items": {}}
    assert p["none"] == {}
    assert p["obj"]["properties"]["y"] == {"type": "number"}
    with pytest.raises(TypeError):
        infer_schema([1, 2], "x")  # type: ignore[arg-type]


def _same(a: Any, b: Any) -> bool:
    """Equal JSON values, floats bit for bit (the sign of zero included)."""
    if isinstance(a, float) and isinstance(b, float):
        return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, dict) and isinstance(b, dict):
        return list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    return type(a) is type(b) and a == b


arrays = st.builds(
    lambda shape, scale, seed: np.random.default_rng(seed).normal(size=shape) * scale,
    st.lists(st.integers(0, 4), min_size=1, max_size=4).map(tuple),
    st.sampled_from([1e-8, 1e-3, 1.0, 1e3, 1e12]),
    st.integers(0, 2**32 - 1),
)
top_values = (
    leaves
    | arrays
    | st.lists(finite_or_not, max_size=4)
    | st.just(np.array([1.0, np.nan, -np.inf]))
    | st.just(np.arange(4, dtype=np.int32))
    | st.just(np.array([True, False]))
    | st.just(np.float64(-0.0))
    | st.just(np.bool_(True))
)


@settings(max_examples=300, deadline=None)
@given(st.dictionaries(st.text(max_size=5), top_values, max_size=6), st.sampled_from([0, 3, 6]))
def test_fast_encoder_with_decimals_matches_the_reference(
    payload: dict[str, Any], decimals: int
) -> None:
    """The compiled path for top-level float arrays writes what `to_jsonable` (arrays rounded,
    non-finite as null) gives, number for number."""
    fast = _strict_loads(make_json_encoder(decimals)(payload))
    reference = json.loads(json.dumps(to_jsonable(payload, decimals), allow_nan=False))
    assert _same(fast, reference)


# Payloads of a few "topics": each group shares its keys, as a topic's payloads do.
_topic_payloads = st.lists(st.text(max_size=3), max_size=4, unique=True).flatmap(
    lambda keys: st.lists(st.fixed_dictionaries({k: top_values for k in keys}), max_size=4)
)


@settings(max_examples=200, deadline=None)
@given(
    st.lists(_topic_payloads, max_size=3).flatmap(
        lambda groups: st.permutations([p for group in groups for p in group])
    ),
    st.sampled_from([None, 0, 6]),
)
def test_batch_encoding_writes_each_payloads_bytes(
    payloads: list[dict[str, Any]], decimals: int | None
) -> None:
    """`many` (column by column, the float arrays in one compiled call) writes the bytes one
    call per payload writes, in order."""
    encode = make_json_encoder(decimals)
    assert encode.many(payloads) == [encode(p) for p in payloads]
