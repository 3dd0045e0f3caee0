"""Quintic time profiles on the normalised time tau in [0, 1] (pure functions).

`min_jerk`: s = 10 tau^3 - 15 tau^4 + 6 tau^5, rest to rest (s' = s'' = 0 at both ends), and
s(1) == 1.0 exactly in floating point, so a profile p0 + s (p1 - p0) ends exactly at p1.

`hermite`: the quintic Hermite basis with zero accelerations at both ends,
p(tau) = (1 - s) p0 + s p1 + T (g0 v0 + g1 v1), where s is the min-jerk blend,
g0 = tau - 6 tau^3 + 8 tau^4 - 3 tau^5 (unit start slope, zero end slope) and
g1 = -4 tau^3 + 7 tau^4 - 3 tau^5 (zero start slope, unit end slope); T is the segment
duration and v0, v1 the end velocities. With v0 = v1 = 0 it is the min-jerk blend.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


def min_jerk(tau: float) -> tuple[float, float, float]:
    """Min-jerk blend s(tau) and its derivatives ds/dtau, d2s/dtau2 (tau clipped to [0, 1])."""
    p = 0.0 if tau < 0.0 else (1.0 if tau > 1.0 else tau)
    q = 1.0 - p
    s = p * p * p * (10.0 - 15.0 * p + 6.0 * p * p)
    ds = 30.0 * p * p * q * q
    dds = 60.0 * p * q * (1.0 - 2.0 * p)
    return s, ds, dds


def min_jerk_array(tau: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Vectorised `min_jerk`: arrays of s, ds/dtau, d2s/dtau2 with the shape of `tau`."""
    p = np.clip(tau, 0.0, 1.0)
    q = 1.0 - p
    p2 = p * p
    s = p2 * p * (10.0 - 15.0 * p + 6.0 * p2)
    ds = 30.0 * p2 * q * q
    dds = 60.0 * p * q * (1.0 - 2.0 * p)
    return s, ds, dds


def hermite(tau: float) -> tuple[float, float, float, float, float, float]:
    """Quintic Hermite basis at tau (clipped to [0, 1]): (s, ds, g0, dg0, g1, dg1).

    Derivatives are with respect to tau; see the module docstring for the formula.
    """
    p = 0.0 if tau < 0.0 else (1.0 if tau > 1.0 else tau)
    q = 1.0 - p
    p2 = p * p
    p3 = p2 * p
    s = p3 * (10.0 - 15.0 * p + 6.0 * p2)
    ds = 30.0 * p2 * q * q
    g0 = p - 6.0 * p3 + 8.0 * p3 * p - 3.0 * p3 * p2
    dg0 = 1.0 - 18.0 * p2 + 32.0 * p3 - 15.0 * p2 * p2
    g1 = -4.0 * p3 + 7.0 * p3 * p - 3.0 * p3 * p2
    dg1 = -12.0 * p2 + 28.0 * p3 - 15.0 * p2 * p2
    return s, ds, g0, dg0, g1, dg1
