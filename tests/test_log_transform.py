"""Tests of locoplan.log.transform.Transform."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from locoplan.log.transform import Transform


def test_arrays_are_copied_into_float_tuples() -> None:
    p = np.array([1.0, 2.0, 3.0])
    tr = Transform("world", "base", p, np.array([0.0, 0.0, 0.0, 1.0]))
    p[0] = 99.0
    assert tr.translation == (1.0, 2.0, 3.0)
    assert tr.rotation == (0.0, 0.0, 0.0, 1.0)
    assert Transform("world", "base", [1, 2, 3], (0, 0, 0, 1)).translation == (1.0, 2.0, 3.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        tr.parent_frame = "x"  # type: ignore[misc]


def test_bad_transforms_are_rejected() -> None:
    with pytest.raises(ValueError, match="translation"):
        Transform("world", "base", [1.0, 2.0], [0, 0, 0, 1])
    with pytest.raises(ValueError, match="rotation"):
        Transform("world", "base", [1.0, 2.0, 3.0], [0, 0, 1])
    with pytest.raises(ValueError, match="itself"):
        Transform("base", "base", [0, 0, 0], [0, 0, 0, 1])
    with pytest.raises(ValueError, match="non-empty"):
        Transform("", "base", [0, 0, 0], [0, 0, 0, 1])
