"""Tests of locoplan.log.scene: arrow geometry and the item constructors' checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from locoplan.log.scene import (
    Rgba,
    box,
    force_arrow,
    line_strip,
    quaternion_x_to,
    sphere,
)


def _rotate(q: tuple[float, float, float, float], v: np.ndarray) -> np.ndarray:
    """Rotate v by the unit quaternion q = (x, y, z, w)."""
    u, w = np.array(q[:3]), q[3]
    return v + 2.0 * w * np.cross(u, v) + 2.0 * np.cross(u, np.cross(u, v))


@pytest.mark.parametrize(
    "direction",
    [(1, 0, 0), (-1, 0, 0), (0, 0, 1), (0, -2, 0), (1, 1, 1), (-1, 1e-9, 0), (0.3, -0.4, -5)],
)
def test_quaternion_x_to_turns_x_onto_the_direction(direction: tuple[float, ...]) -> None:
    d = np.array(direction, dtype=float)
    q = quaternion_x_to((d[0], d[1], d[2]))
    assert math.isclose(float(np.linalg.norm(q)), 1.0, abs_tol=1e-12)  # unit, to rounding
    # 1e-8: the nearly antiparallel case (1e-9 off) falls into the half-turn branch.
    np.testing.assert_allclose(_rotate(q, np.array([1.0, 0, 0])), d / np.linalg.norm(d), atol=1e-8)


def test_random_directions() -> None:
    rng = np.random.default_rng(1)
    for d in rng.normal(size=(200, 3)):
        q = quaternion_x_to((d[0], d[1], d[2]))
        # 1e-12: a few roundings in a unit-norm computation.
        np.testing.assert_allclose(
            _rotate(q, np.array([1.0, 0, 0])), d / np.linalg.norm(d), atol=1e-12
        )


def test_zero_vector_gives_identity() -> None:
    assert quaternion_x_to((0.0, 0.0, 0.0)) == (0.0, 0.0, 0.0, 1.0)


def test_force_arrow_scales_the_force() -> None:
    arrow = force_arrow(
        "f", np.array([1.0, 2.0, 0.0]), np.array([0.0, 30.0, 40.0]), scale_m_per_N=0.01
    )
    assert arrow.start == (1.0, 2.0, 0.0)
    assert arrow.vector == pytest.approx((0.0, 0.3, 0.4), abs=1e-15)  # 50 N -> 0.5 m
    with pytest.raises(ValueError, match="scale"):
        force_arrow("f", [0, 0, 0], [0, 0, 1], scale_m_per_N=0.0)


def test_constructors_check_shapes_and_values() -> None:
    assert box("b", [0, 0, 0], np.array([1.0, 2.0, 3.0])).size == (1.0, 2.0, 3.0)
    with pytest.raises(ValueError, match="size"):
        box("b", [0, 0, 0], [1, 2])
    with pytest.raises(ValueError, match="negative"):
        box("b", [0, 0, 0], [1, -2, 1])
    with pytest.raises(ValueError, match="orientation"):
        box("b", [0, 0, 0], [1, 1, 1], orientation=[0, 0, 1])
    with pytest.raises(ValueError, match="negative"):
        sphere("s", [0, 0, 0], -0.1)
    assert line_strip("l", np.zeros((4, 3))).points == ((0.0, 0.0, 0.0),) * 4
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        line_strip("l", np.zeros((4, 2)))
    with pytest.raises(ValueError, match="outside"):
        Rgba(1.2, 0.0, 0.0)
