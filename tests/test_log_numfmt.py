"""Tests of locoplan.log.numfmt: the compiled JSON text of rounded float arrays parses back to
`np.round`'s doubles bit for bit (no tolerance: that is the kernel's promise)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from locoplan.log.numfmt import MAX_DECIMALS, RoundedJson, rounded_json


def _same_bits(got: object, want: np.ndarray) -> bool:
    got_arr = np.array(got, dtype=float)  # None (JSON null) becomes NaN
    return (
        got_arr.shape == want.shape
        and np.array_equal(got_arr, want, equal_nan=True)
        and np.array_equal(np.signbit(got_arr), np.signbit(want))
    )


def _expected(a: np.ndarray, decimals: int) -> np.ndarray:
    want = np.round(a, decimals)
    return np.where(np.isfinite(want), want, np.nan)  # non-finite values are written as null


values = st.floats(allow_nan=True, allow_infinity=True, width=64) | st.floats(-1e3, 1e3)


@settings(max_examples=300, deadline=None)
@given(
    hnp.arrays(np.float64, hnp.array_shapes(min_dims=1, max_dims=3, max_side=5), elements=values),
    st.integers(0, 9),
)
def test_text_parses_back_to_np_round(a: np.ndarray, decimals: int) -> None:
    text = rounded_json(a, decimals)
    with np.errstate(over="ignore"):  # huge values overflow to inf, which counts as big
        big = np.isfinite(a) & (np.abs(a) * 10.0**decimals >= 2.0**53)
    if big.any():
        assert text is None  # beyond exact integers the caller takes the slow path
        return
    assert text is not None
    assert _same_bits(json.loads(text), _expected(a, decimals))


def test_format_details() -> None:
    a = np.array([[1e-6, -0.0, 2.5], [100.0, 123456.7891234, -1e-7]])
    assert rounded_json(a, 6) == b"[[0.000001,-0.0,2.5],[100.0,123456.789123,-0.0]]"
    assert rounded_json(np.array([np.nan, np.inf, 0.5]), 2) == b"[null,null,0.5]"
    assert rounded_json(np.array([2.5, 3.5, -2.5]), 0) == b"[2.0,4.0,-2.0]"  # half to even
    assert rounded_json(np.zeros((2, 0)), 6) is None
    assert rounded_json(np.zeros((1, 1, 1, 1)), 6) is None  # 4-D: the caller's slow path
    assert rounded_json(np.ones(2), MAX_DECIMALS + 1) is None
    with pytest.raises(ValueError):
        RoundedJson(-1)


def test_views_and_read_only_arrays() -> None:
    rng = np.random.default_rng(1)
    x = rng.normal(size=(20, 6)) * 30
    for view in (x[:, 3:6], x[::2], x.T, np.frombuffer(x.tobytes()).reshape(20, 6)):
        text = rounded_json(view, 6)
        assert text is not None
        assert _same_bits(json.loads(text), _expected(view, 6))


@settings(max_examples=150, deadline=None)
@given(
    st.lists(
        hnp.arrays(
            np.float64,
            hnp.array_shapes(min_dims=1, max_dims=4, min_side=0, max_side=4),
            elements=values,
        ),
        max_size=6,
    ),
    st.integers(0, 9),
)
def test_many_writes_what_one_call_each_writes(arrays: list[np.ndarray], decimals: int) -> None:
    """The batch (one kernel call) gives each array's bytes, None where `__call__` gives None
    (too large, empty, 4-D) without shifting the texts after it."""
    encode = RoundedJson(decimals)
    assert encode.many(arrays) == [encode(a) for a in arrays]
