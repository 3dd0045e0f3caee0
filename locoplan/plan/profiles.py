"""Quintic time profiles on the normalised time tau in [0, 1] (pure functions).

`min_jerk`: s = 10 tau^3 - 15 tau^4 + 6 tau^5, rest to rest (s' = s'' = 0 at both ends), and
s(1) == 1.0 exactly in floating point, so a profile p0 + s (p1 - p0) ends exactly at p1.

`hermite`: the quintic Hermite basis with zero accelerations at both ends,
p(tau) = (1 - s) p0 + s p1 + T (g0 v0 + g1 v1), where s is the min-jerk blend,
g0 = tau - 6 tau^3 + 8 tau^4 - 3 tau^5 (unit start slope, zero end slope) and
g1 = -4 tau^3 + 7 tau^4 - 3 tau^5 (zero start slope, unit end slope); T is the segment
duration and v0, v1 the end velocities. With v0 = v1 = 0 it is the min-jerk blend.

`cruise`: rest to rest with a constant-velocity middle. The velocity rises along the cubic
smoothstep 3u^2 - 2u^3 over the first fraction r of the time, holds 1 / (1 - r) and falls back
symmetrically over the last r, so s' peaks at 1 / (1 - r) (the min-jerk blend: 1.875) and
|s''| at 1.5 / (r (1 - r)) (min-jerk: 5.77); s'' is continuous and zero at both ends. s(1) is
1.0 exactly (the end is evaluated as 1 - ramp(0)).
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


def hermite_second(tau: float) -> tuple[float, float, float]:
    """Second derivatives with respect to tau of `hermite`'s s, g0 and g1 at tau (clipped to
    [0, 1]): (d2s, d2g0, d2g1). All three are zero at both ends."""
    p = 0.0 if tau < 0.0 else (1.0 if tau > 1.0 else tau)
    p2 = p * p
    dds = 60.0 * p * (1.0 - p) * (1.0 - 2.0 * p)
    ddg0 = -36.0 * p + 96.0 * p2 - 60.0 * p2 * p
    ddg1 = -24.0 * p + 84.0 * p2 - 60.0 * p2 * p
    return dds, ddg0, ddg1


# Ramp fraction of `cruise`: the velocity rises over the first CRUISE_RAMP of a walk or turn
# and falls over the last. At 1/2 there is no cruise left and the peak s' (2) exceeds the
# min-jerk blend's; at 1/3 the peak s' is 1.5 and the peak s'' 1.17x min-jerk's. Ramps of one
# gait period (the time the footholds take to follow a change of speed) were tried first: they
# cut the peak of long walks to T / (T - period) of the average but raised the peak
# acceleration to 1.5 v / period, 0.97 m/s^2 for the 0.5 m walk of issue 12's 6 kg walk-carry
# example (min-jerk: 0.53), which then fell at the walk's start with the stance hip pitch and
# roll at their limits. A third of the duration keeps the peak acceleration within 1.17x
# min-jerk's on every task.
CRUISE_RAMP = 1.0 / 3.0


def peak_rate(amount: float, duration: float) -> float:
    """Peak rate (amount / s) of a walk or turn covering `amount` in `duration` s along the
    cruise blend: the average times 1 / (1 - CRUISE_RAMP)."""
    return abs(amount) / duration / (1.0 - CRUISE_RAMP)


def least_duration(amount: float, max_rate: float) -> float:
    """Shortest duration (s) whose `peak_rate` is within `max_rate` > 0."""
    return abs(amount) / max_rate / (1.0 - CRUISE_RAMP)


def cruise(tau: float) -> tuple[float, float, float]:
    """Cruise blend s(tau) and ds/dtau, d2s/dtau2 with ramps of CRUISE_RAMP (tau clipped to
    [0, 1]); see the module docstring."""
    p = 0.0 if tau < 0.0 else (1.0 if tau > 1.0 else tau)
    ramp = CRUISE_RAMP
    vp = 1.0 / (1.0 - ramp)
    if p <= ramp:
        u = p / ramp
        return (
            vp * ramp * u * u * u * (1.0 - 0.5 * u),
            vp * u * u * (3.0 - 2.0 * u),
            6.0 * vp * u * (1.0 - u) / ramp,
        )
    if p < 1.0 - ramp:
        return vp * (p - 0.5 * ramp), vp, 0.0
    u = (1.0 - p) / ramp
    return (
        1.0 - vp * ramp * u * u * u * (1.0 - 0.5 * u),
        vp * u * u * (3.0 - 2.0 * u),
        -6.0 * vp * u * (1.0 - u) / ramp,
    )


def cruise_array(tau: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Vectorised `cruise`: arrays of s, ds/dtau, d2s/dtau2 with the shape of `tau`."""
    p = np.clip(tau, 0.0, 1.0)
    ramp = CRUISE_RAMP
    vp = 1.0 / (1.0 - ramp)
    rise = p <= ramp
    fall = p >= 1.0 - ramp
    u = np.where(rise, p / ramp, np.where(fall, (1.0 - p) / ramp, 0.0))
    edge_s = vp * ramp * u * u * u * (1.0 - 0.5 * u)
    edge_ds = vp * u * u * (3.0 - 2.0 * u)
    edge_dds = 6.0 * vp * u * (1.0 - u) / ramp
    s = np.where(rise, edge_s, np.where(fall, 1.0 - edge_s, vp * (p - 0.5 * ramp)))
    ds = np.where(rise | fall, edge_ds, vp)
    dds = np.where(rise, edge_dds, np.where(fall, -edge_dds, 0.0))
    return s, ds, dds
