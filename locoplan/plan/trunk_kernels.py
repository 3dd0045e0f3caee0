"""Compiled evaluation of the trunk reference (numba, `cache=True`).

Why compiled: the controller asks for the trunk reference at every MPC update, at the
horizon's steps, now, the touchdowns inside the horizon and the held load's lead times (some
45 times at once, 10 ms apart), and `TrunkPath.evaluate` as numpy was some forty array calls
of 2-4 us each, 0.1 ms an update (2026-12-08, package transfer: the largest single piece of
the reference pipeline around the MPC). Compiled it is the arithmetic alone. Each formula is
written as `profiles.cruise_array` and the numpy `TrunkPath.evaluate` wrote it, operation for
operation in the same order (no fast-math: no reassociation, no fused multiply-add), so the
results are those of the numpy code bit for bit (tests/test_plan_trunk.py checks that).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numba import njit

from locoplan.plan.profiles import CRUISE_RAMP

FloatArray = npt.NDArray[np.float64]


@njit(cache=True, inline="always")
def _cruise(tau: float) -> tuple[float, float, float]:
    """`profiles.cruise_array` at one tau: (s, ds/dtau, d2s/dtau2)."""
    p = min(max(tau, 0.0), 1.0)
    ramp = CRUISE_RAMP
    vp = 1.0 / (1.0 - ramp)
    rise = p <= ramp
    fall = p >= 1.0 - ramp
    if rise:
        u = p / ramp
    elif fall:
        u = (1.0 - p) / ramp
    else:
        u = 0.0
    edge_s = vp * ramp * u * u * u * (1.0 - 0.5 * u)
    edge_ds = vp * u * u * (3.0 - 2.0 * u)
    edge_dds = 6.0 * vp * u * (1.0 - u) / ramp
    if rise:
        return edge_s, edge_ds, edge_dds
    if fall:
        return 1.0 - edge_s, edge_ds, -edge_dds
    return vp * (p - 0.5 * ramp), vp, 0.0


@njit(cache=True)
def evaluate(
    times: FloatArray,
    t0: FloatArray,
    dur: FloatArray,
    p0: FloatArray,
    dp: FloatArray,
    yaw0: FloatArray,
    dyaw: FloatArray,
    height: float,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """The trunk reference at ``times`` (n,) from `TrunkPath`'s segment arrays (with their
    leading sentinel, t0 = -inf): position, velocity, acceleration (n, 3), yaw, yaw rate,
    yaw acceleration (n,)."""
    n = times.shape[0]
    pos = np.empty((n, 3))
    vel = np.zeros((n, 3))
    acc = np.zeros((n, 3))
    yaw = np.empty(n)
    rate = np.empty(n)
    yaw_acc = np.empty(n)
    for k in range(n):
        t = times[k]
        # np.searchsorted(t0, t, side="right") - 1: the last segment starting at or before t.
        i = np.searchsorted(t0, t, side="right") - 1
        d = dur[i]
        s, ds, dds = _cruise((t - t0[i]) / d)
        v = ds / d
        a = dds / (d * d)
        pos[k, 0] = p0[i, 0] + s * dp[i, 0]
        pos[k, 1] = p0[i, 1] + s * dp[i, 1]
        pos[k, 2] = height
        vel[k, 0] = v * dp[i, 0]
        vel[k, 1] = v * dp[i, 1]
        acc[k, 0] = a * dp[i, 0]
        acc[k, 1] = a * dp[i, 1]
        yaw[k] = yaw0[i] + s * dyaw[i]
        rate[k] = v * dyaw[i]
        yaw_acc[k] = a * dyaw[i]
    return pos, vel, acc, yaw, rate, yaw_acc


def warm_up() -> None:
    """Compile (or load from the cache) `evaluate` for the types `TrunkPath` passes."""
    t0 = np.array([-np.inf, 0.0])
    two = np.zeros((2, 2))
    evaluate(np.zeros(2), t0, np.ones(2), two, two, np.zeros(2), np.zeros(2), 0.5)
