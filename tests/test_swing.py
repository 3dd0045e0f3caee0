"""Swing curves hit their end points at rest; derivatives match finite differences."""

from __future__ import annotations

import numpy as np
import pytest

from locoplan.control.swing import (
    bump,
    min_jerk,
    raibert_foothold,
    smoothstep,
    smoothstep_array,
    swing_point,
)


def test_swing_hits_end_points_at_rest() -> None:
    p0 = np.array([0.0, 0.1, 0.0])
    p1 = np.array([0.2, 0.12, 0.0])
    start = swing_point(p0, p1, 0.1, 0.0, 0.15)
    end = swing_point(p0, p1, 0.1, 1.0, 0.15)
    # Exact polynomials: only rounding error remains.
    np.testing.assert_allclose(start.position, p0, atol=1e-15)
    np.testing.assert_allclose(end.position, p1, atol=1e-15)
    for pt in (start, end):
        np.testing.assert_allclose(pt.velocity, 0.0, atol=1e-12)
        np.testing.assert_allclose(pt.acceleration, 0.0, atol=1e-12)
    mid = swing_point(p0, p1, 0.1, 0.5, 0.15)
    assert mid.position[2] == pytest.approx(0.1, abs=1e-12)


@pytest.mark.parametrize("phi", [0.1, 0.3, 0.5, 0.77, 0.9])
def test_derivatives_match_finite_differences(phi: float) -> None:
    # Central differences with h = 1e-6 on quintic/sextic polynomials: error ~ h^2 * f''' ~ 1e-10.
    h = 1e-6
    for fn in (min_jerk, bump):
        _, df, ddf = fn(phi)
        fp, dfp, _ = fn(phi + h)
        fm, dfm, _ = fn(phi - h)
        assert df == pytest.approx((fp - fm) / (2 * h), abs=1e-7)
        assert ddf == pytest.approx((dfp - dfm) / (2 * h), abs=1e-6)
    p0, p1, T = np.zeros(3), np.array([0.3, -0.1, 0.02]), 0.2
    a = swing_point(p0, p1, 0.12, phi + h / T, T).position
    b = swing_point(p0, p1, 0.12, phi - h / T, T).position
    np.testing.assert_allclose(
        swing_point(p0, p1, 0.12, phi, T).velocity, (a - b) / (2 * h), atol=1e-6
    )


def test_raibert_at_desired_speed_is_neutral_point() -> None:
    v = np.array([0.4, 0.0])
    p = raibert_foothold(np.zeros(2), v, v, 0.2, 0.1)
    np.testing.assert_allclose(p, [0.04, 0.0])


def test_smoothstep_clips_and_matches_its_array_form() -> None:
    u = np.array([-0.5, 0.0, 0.25, 0.5, 0.8, 1.0, 1.7])
    # 3 u^2 - 2 u^3 on [0, 1]: 0.25 -> 0.15625, 0.5 -> 0.5, 0.8 -> 0.896 (exact in binary up
    # to rounding); clipped outside.
    expected = np.array([0.0, 0.0, 0.15625, 0.5, 0.896, 1.0, 1.0])
    np.testing.assert_allclose(smoothstep_array(u), expected, atol=1e-15)
    np.testing.assert_allclose([smoothstep(float(x)) for x in u], expected, atol=1e-15)
    # Zero slope at both ends: central differences (h = 1e-6) about 0 and 1 from inside.
    h = 1e-6
    assert (smoothstep(2 * h) - smoothstep(0.0)) / (2 * h) == pytest.approx(0.0, abs=1e-5)
    assert (smoothstep(1.0) - smoothstep(1.0 - 2 * h)) / (2 * h) == pytest.approx(0.0, abs=1e-5)
