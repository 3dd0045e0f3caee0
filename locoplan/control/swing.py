"""Swing-foot trajectories and the paper's Raibert foothold rule (pure functions).

Horizontal motion follows a quintic min-jerk blend s(phi); the height adds a bump
b(phi) = 64 phi^3 (1 - phi)^3, which peaks at 1 for phi = 1/2 and has zero velocity and
acceleration at both ends, so lift-off and touchdown are gentle and the foot arrives at rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class SwingPoint:
    """Desired foot position (3,), velocity (3,) and acceleration (3,), world frame, SI units."""

    position: FloatArray
    velocity: FloatArray
    acceleration: FloatArray


def min_jerk(phi: float) -> tuple[float, float, float]:
    """Quintic blend s(phi) = 10 phi^3 - 15 phi^4 + 6 phi^5 and its first two derivatives."""
    p = min(max(phi, 0.0), 1.0)
    s = p**3 * (10.0 - 15.0 * p + 6.0 * p * p)
    ds = 30.0 * p * p * (1.0 - p) ** 2
    dds = 60.0 * p * (1.0 - p) * (1.0 - 2.0 * p)
    return s, ds, dds


def smoothstep(u: float) -> float:
    """Cubic blend 3 c^2 - 2 c^3 of c = u clipped to [0, 1]: from 0 to 1 with zero slope at
    both ends (the load ramps, grip blends and lean ramps of the controller)."""
    c = 0.0 if u < 0.0 else (1.0 if u > 1.0 else u)
    return c * c * (3.0 - 2.0 * c)


def smoothstep_array(u: FloatArray) -> FloatArray:
    """Element-wise `smoothstep` of an array (same shape)."""
    c = np.minimum(np.maximum(u, 0.0), 1.0)  # np.clip's dispatch costs 1 us more a call
    return c * c * (3.0 - 2.0 * c)


def bump(phi: float) -> tuple[float, float, float]:
    """b(phi) = 64 phi^3 (1 - phi)^3 (peak 1 at phi = 1/2) and its first two derivatives."""
    p = min(max(phi, 0.0), 1.0)
    q = 1.0 - p
    b = 64.0 * p**3 * q**3
    db = 192.0 * (p * p * q**3 - p**3 * q * q)
    ddb = 192.0 * (2.0 * p * q**3 - 6.0 * p * p * q * q + 2.0 * p**3 * q)
    return b, db, ddb


def swing_point(
    p_start: FloatArray, p_end: FloatArray, height: float, phase: float, duration: float
) -> SwingPoint:
    """Point of a swing from `p_start` to `p_end` (world, m) lifting `height` m above the
    straight line, at `phase` in [0, 1] of a swing lasting `duration` s."""
    s, ds, dds = min_jerk(phase)
    b, db, ddb = bump(phase)
    delta = p_end - p_start
    up = np.array([0.0, 0.0, height])
    pos = p_start + s * delta + b * up
    vel = (ds * delta + db * up) / duration
    acc = (dds * delta + ddb * up) / duration**2
    return SwingPoint(pos, vel, acc)


def raibert_foothold(
    p_hip_xy: FloatArray,
    v_com_xy: FloatArray,
    v_des_xy: FloatArray,
    stance_time: float,
    gain: float,
) -> FloatArray:
    """The paper's foot placement p = p_hip + v dt/2 + k (v - v_des) (xy, world, m).

    `p_hip_xy` is the hip's projection at touchdown, `stance_time` the coming stance duration.
    """
    return p_hip_xy + v_com_xy * stance_time / 2.0 + gain * (v_com_xy - v_des_xy)
