"""The line feet's support region and the nearest point inside it (analytic cases, to 1e-12)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from locoplan.control.support import clamp_into_support, convex_hull, foot_segments

TOE, HEEL = 0.09, 0.06


def _stance(width: float = 0.16, yaw: float = 0.0) -> np.ndarray:
    """Hull of two parallel feet `width` apart, side by side about the origin, turned by yaw."""
    c, s = math.cos(yaw), math.sin(yaw)
    feet = np.array([[-s * width / 2, c * width / 2, 0.0], [s * width / 2, -c * width / 2, 0.0]])
    return convex_hull(foot_segments(feet, np.array([yaw, yaw]), TOE, HEEL))


def test_the_hull_of_two_parallel_feet_is_their_rectangle_counter_clockwise() -> None:
    hull = _stance()
    assert hull.shape == (4, 2)
    assert sorted(map(tuple, hull.round(12))) == sorted(
        [(-HEEL, -0.08), (TOE, -0.08), (TOE, 0.08), (-HEEL, 0.08)]
    )
    x, y = hull[:, 0], hull[:, 1]
    area = 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
    assert area == pytest.approx((TOE + HEEL) * 0.16, abs=1e-12)  # positive: CCW


def test_a_point_inside_the_shrunk_support_is_kept() -> None:
    p = np.array([0.01, 0.03])
    np.testing.assert_array_equal(clamp_into_support(p, _stance(), 0.02), p)


def test_a_point_beside_the_feet_comes_to_the_margin_inside_the_outer_edge() -> None:
    """12 cm left of the left foot (the walk of envelope seed 16180 locomotion-000 ended so
    far from its reference): straight across to 2 cm inside the left edge."""
    out = clamp_into_support(np.array([0.01, 0.20]), _stance(), 0.02)
    np.testing.assert_allclose(out, [0.01, 0.06], atol=1e-12)


def test_a_point_beyond_a_corner_comes_to_the_shrunk_corner() -> None:
    out = clamp_into_support(np.array([0.3, 0.3]), _stance(), 0.02)
    np.testing.assert_allclose(out, [TOE - 0.02, 0.06], atol=1e-12)


def test_turned_feet_give_the_same_answer_turned() -> None:
    yaw = math.radians(-94.7)
    c, s = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s], [s, c]])
    out = clamp_into_support(rot @ np.array([0.01, 0.20]), _stance(yaw=yaw), 0.02)
    np.testing.assert_allclose(out, rot @ np.array([0.01, 0.06]), atol=1e-12)


def test_feet_too_close_for_the_margin_give_the_centroid() -> None:
    hull = _stance(width=0.02)
    out = clamp_into_support(np.array([0.0, 0.5]), hull, 0.02)
    np.testing.assert_allclose(out, hull.mean(axis=0), atol=1e-12)
