"""The line feet's support region and the nearest point inside it (analytic cases, to 1e-12)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from locoplan.control.support import (
    chord_offsets,
    clamp_into_support,
    convex_hull,
    foot_segments,
    share_between_feet,
)

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


def test_chord_offsets_measure_a_point_from_the_middle_of_the_support_along_each_direction() -> (
    None
):
    """Two parallel feet side by side: along x the chord runs from the heel (-HEEL) to the toe
    (TOE), whose middle is (TOE - HEEL) / 2 ahead of the sole line, so a point at x stands
    x - (TOE - HEEL) / 2 ahead of it; backwards the sign turns; across (y) the chord's middle
    is the stance's middle line. A point outside the hull, or a hull of fewer than three
    vertices, gives NaN."""
    hull = _stance()
    dirs = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0]])
    for x, y in [(0.0, 0.0), (0.03, 0.02), (-0.04, -0.05)]:
        got = chord_offsets(np.array([x, y]), dirs, hull)
        np.testing.assert_allclose(got, [x - (TOE - HEEL) / 2, (TOE - HEEL) / 2 - x, y], atol=1e-12)
    assert np.isnan(chord_offsets(np.array([0.2, 0.0]), dirs, hull)).all()
    assert np.isnan(chord_offsets(np.zeros(2), dirs, hull[:2])).all()


def test_chord_offsets_of_staggered_feet_see_the_back_edge_between_the_heels() -> None:
    """Left foot at x = 0, right foot 0.04 m ahead (a walk's last step landing ahead of its
    plan): on the middle line y = 0 the back edge runs between the heels, at -HEEL + 0.02,
    and the front edge between the toes, at TOE + 0.02; the point x = 0 stands 0.02 m plus
    (TOE - HEEL) / 2 behind the middle of that chord."""
    feet = np.array([[0.0, 0.08, 0.0], [0.04, -0.08, 0.0]])
    hull = convex_hull(foot_segments(feet, np.zeros(2), TOE, HEEL))
    got = chord_offsets(np.zeros(2), np.array([[1.0, 0.0]]), hull)
    assert got[0] == pytest.approx(-(0.02 + (TOE - HEEL) / 2), abs=1e-12)


def test_a_point_between_the_middle_shares_of_the_feet_is_kept() -> None:
    c0, c1 = np.array([0.0, 0.08]), np.array([0.0, -0.08])
    for p in ([0.0, 0.0], [0.05, 0.04], [-0.03, -0.04]):
        np.testing.assert_allclose(share_between_feet(np.array(p), c0, c1, 0.25), p, atol=1e-12)


def test_a_point_near_one_foot_moves_along_the_feet_axis_to_the_share() -> None:
    """Over the left foot (y 0.08) or beyond it, with 0.25: to a quarter of the 0.16 m from
    it (y 0.04), its offset along the feet (x) kept; the same beyond the right foot."""
    c0, c1 = np.array([0.0, 0.08]), np.array([0.0, -0.08])
    np.testing.assert_allclose(
        share_between_feet(np.array([0.03, 0.12]), c0, c1, 0.25), [0.03, 0.04], atol=1e-12
    )
    np.testing.assert_allclose(
        share_between_feet(np.array([-0.02, -0.07]), c0, c1, 0.25), [-0.02, -0.04], atol=1e-12
    )


def test_staggered_turned_feet_give_the_lever_rule_share() -> None:
    """Feet 0.2 m apart along a 30 deg axis: a point at 10 % from c0 goes to 25 %."""
    axis = np.array([math.cos(math.pi / 6), math.sin(math.pi / 6)])
    normal = np.array([-axis[1], axis[0]])
    c0 = np.array([0.1, -0.2])
    c1 = c0 + 0.2 * axis
    p = c0 + 0.02 * axis + 0.03 * normal
    np.testing.assert_allclose(
        share_between_feet(p, c0, c1, 0.25), c0 + 0.05 * axis + 0.03 * normal, atol=1e-12
    )


def test_feet_on_one_spot_leave_the_point() -> None:
    c = np.array([0.1, 0.1])
    np.testing.assert_allclose(share_between_feet(np.array([0.3, 0.0]), c, c, 0.25), [0.3, 0.0])
