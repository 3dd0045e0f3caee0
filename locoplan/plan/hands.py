"""Hand target tracks: piecewise quintic segments between waypoints tagged with a frame.

A waypoint is a point (and optionally a velocity) either in "world" or in "trunk" (relative to
the trunk origin, in the trunk's yaw-only frame). A segment blends its two waypoints with the
zero-acceleration quintic Hermite of `locoplan.plan.profiles`; both ends are mapped to the world
with the trunk pose at the evaluation time, so a "trunk" end follows the real trunk while a
"world" end stays put. Between segments a hand holds the end waypoint of its last segment
(before its first segment, the track's initial waypoint: the default pose in trunk).

Evaluation is written with plain floats: it runs every control tick (1 kHz).
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass
from typing import Literal

from locoplan.plan.profiles import hermite, hermite_second

Frame = Literal["trunk", "world"]
Vec3 = tuple[float, float, float]
ZERO3: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class HandWaypoint:
    """A hand target point (m) in `frame`, with a velocity (m/s) in the same frame (for
    "trunk": relative to the trunk, trunk axes). Velocities are zero except in a throw."""

    point: Vec3
    frame: Frame
    velocity: Vec3 = ZERO3


@dataclass(frozen=True, slots=True)
class HandSegment:
    """Blend from `start` at t0 to `end` at t1 (s). `label` names the phase ("reach",
    "squeeze", "grip", "raise", "carry", "settle", "pull", "hover", "lower", "open", "retract",
    "windup", "accelerate", "follow", "return"); `task_index` is the scenario task it belongs
    to."""

    t0: float
    t1: float
    start: HandWaypoint
    end: HandWaypoint
    task_index: int
    label: str


@dataclass(frozen=True, slots=True)
class BasePose:
    """Trunk pose used to map "trunk" waypoints to the world: origin (m), cos/sin of the yaw,
    linear velocity (m/s) and yaw rate (rad/s), world frame."""

    x: float
    y: float
    z: float
    c: float
    s: float
    vx: float
    vy: float
    vz: float
    wz: float


def _to_world(w: HandWaypoint, b: BasePose) -> tuple[Vec3, Vec3, Vec3, Vec3]:
    """World position (m) and its velocity (m/s) of a waypoint's point, and the waypoint's
    velocity vector in world axes (m/s) with its rate of change (m/s^2) due to the trunk's
    rotation."""
    px, py, pz = w.point
    ux, uy, uz = w.velocity
    if w.frame == "world":
        return (px, py, pz), ZERO3, (ux, uy, uz), ZERO3
    rx = b.c * px - b.s * py
    ry = b.s * px + b.c * py
    rux = b.c * ux - b.s * uy
    ruy = b.s * ux + b.c * uy
    return (
        (b.x + rx, b.y + ry, b.z + pz),
        (b.vx - b.wz * ry, b.vy + b.wz * rx, b.vz),
        (rux, ruy, uz),
        (-b.wz * ruy, b.wz * rux, 0.0),
    )


def _turning(w: HandWaypoint, b: BasePose) -> tuple[Vec3, Vec3]:
    """Accelerations (m/s^2) of a waypoint's world point and of its velocity vector due to the
    trunk's motion, for a trunk moving at its present velocity and yaw rate (its own
    accelerations are not measured: the centripetal terms only); zero for a "world" waypoint."""
    if w.frame == "world":
        return ZERO3, ZERO3
    px, py, _ = w.point
    ux, uy, _ = w.velocity
    w2 = b.wz * b.wz
    return (
        (-w2 * (b.c * px - b.s * py), -w2 * (b.s * px + b.c * py), 0.0),
        (-w2 * (b.c * ux - b.s * uy), -w2 * (b.s * ux + b.c * uy), 0.0),
    )


@dataclass(frozen=True, slots=True, eq=False)
class HandTrack:
    """The target of one hand over the whole plan: `initial` waypoint, then `segments`
    (sorted, non-overlapping)."""

    hand: str
    initial: HandWaypoint
    segments: tuple[HandSegment, ...]
    _t0_list: list[float]

    def _segment_at(self, t: float) -> tuple[HandSegment | None, HandWaypoint]:
        """The segment under way at t (s) and its end, or None and the waypoint the hand
        rests at (the initial one before the first segment, else the last segment's end)."""
        k = bisect.bisect_right(self._t0_list, t) - 1
        if k < 0:
            return None, self.initial
        g = self.segments[k]
        return (None if t >= g.t1 else g), g.end

    def evaluate(self, t: float, b: BasePose) -> tuple[Vec3, Vec3]:
        """World position (m) and velocity (m/s) of the hand target at time t."""
        g, rest = self._segment_at(t)
        if g is None:
            p, v, _, _ = _to_world(rest, b)
            return p, v
        T = g.t1 - g.t0
        s, ds, g0, dg0, g1, dg1 = hermite((t - g.t0) / T)
        p0, q0, u0, du0 = _to_world(g.start, b)
        p1, q1, u1, du1 = _to_world(g.end, b)
        r = 1.0 - s
        sdot = ds / T
        pos = (
            r * p0[0] + s * p1[0] + T * (g0 * u0[0] + g1 * u1[0]),
            r * p0[1] + s * p1[1] + T * (g0 * u0[1] + g1 * u1[1]),
            r * p0[2] + s * p1[2] + T * (g0 * u0[2] + g1 * u1[2]),
        )
        vel = (
            r * q0[0]
            + s * q1[0]
            + sdot * (p1[0] - p0[0])
            + dg0 * u0[0]
            + dg1 * u1[0]
            + T * (g0 * du0[0] + g1 * du1[0]),
            r * q0[1]
            + s * q1[1]
            + sdot * (p1[1] - p0[1])
            + dg0 * u0[1]
            + dg1 * u1[1]
            + T * (g0 * du0[1] + g1 * du1[1]),
            r * q0[2]
            + s * q1[2]
            + sdot * (p1[2] - p0[2])
            + dg0 * u0[2]
            + dg1 * u1[2]
            + T * (g0 * du0[2] + g1 * du1[2]),
        )
        return pos, vel

    def acceleration(self, t: float, b: BasePose) -> Vec3:
        """World acceleration (m/s^2) of the hand target at time t: the second time derivative
        of `evaluate`'s position with the trunk moving at `b`'s velocity and yaw rate (the
        hands' feed-forward: a Cartesian PD without it lags a quintic reach by about its
        acceleration over kp; a reach of d in T peaks at 5.77 d / T^2, 28 m/s^2 for 0.3 m in
        0.25 s, 7 cm at kp 400)."""
        g, rest = self._segment_at(t)
        if g is None:
            return _turning(rest, b)[0]
        T = g.t1 - g.t0
        tau = (t - g.t0) / T
        s, ds, g0, dg0, g1, dg1 = hermite(tau)
        dds, ddg0, ddg1 = hermite_second(tau)
        p0, q0, u0, du0 = _to_world(g.start, b)
        p1, q1, u1, du1 = _to_world(g.end, b)
        a0, ddu0 = _turning(g.start, b)
        a1, ddu1 = _turning(g.end, b)
        r = 1.0 - s
        sdot = ds / T
        sddot = dds / (T * T)
        out = [0.0, 0.0, 0.0]
        for i in range(3):
            out[i] = (
                r * a0[i]
                + s * a1[i]
                + 2.0 * sdot * (q1[i] - q0[i])
                + sddot * (p1[i] - p0[i])
                + (ddg0 * u0[i] + ddg1 * u1[i]) / T
                + 2.0 * (dg0 * du0[i] + dg1 * du1[i])
                + T * (g0 * ddu0[i] + g1 * ddu1[i])
            )
        return out[0], out[1], out[2]

    def label_at(self, t: float) -> str | None:
        """The label of the segment under way at t (s), None between and outside segments."""
        g, _ = self._segment_at(t)
        return None if g is None else g.label

    def last_waypoint(self) -> HandWaypoint:
        """Where the hand rests after its last segment."""
        return self.segments[-1].end if self.segments else self.initial

    def busy_until(self) -> float:
        """End time of the last segment (s), -inf without segments."""
        return self.segments[-1].t1 if self.segments else float("-inf")


def make_track(hand: str, initial: HandWaypoint, segments: list[HandSegment]) -> HandTrack:
    """A `HandTrack` from segments in time order."""
    return HandTrack(hand, initial, tuple(segments), [g.t0 for g in segments])
