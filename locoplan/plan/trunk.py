"""Trunk reference: position and yaw of the trunk origin from the locomotion tasks.

Each walk or turn is one `cruise` segment (profiles.py) that starts and ends at rest and
reaches its displacement exactly at the task's end: a walk moves the trunk by its `distance`
expressed in the body frame at the task's start (along a straight line, turning by its optional
`angle` on the way), a turn changes the yaw (position constant).

Why cruise and not min-jerk: the gait limits (scenario/feasibility.py) bound the speed and the
yaw rate a stance foot can follow, and min-jerk peaks at 1.875x the task's average, so a walk at
0.35 m/s asked 0.66 m/s of the legs mid-walk (0.33 m strides at a 0.5 s period against the 0.18
m reach ahead of the hip) and a 90 deg/s turn 169 deg/s; the robot fell behind its reference
and fell (envelope seed 6161: locomotion-038 lagged 0.2 m before it fell). The cruise profile
ramps the velocity up over the first third of the task, holds it and ramps it down over the
last third (profiles.CRUISE_RAMP says why a third): the peak is 1.5x the average and the peak
acceleration 1.17x min-jerk's.
Steps and non-locomotion tasks leave the pose where it is. The height is constant.
Locomotion tasks never overlap, so the segments simply compose end to end.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from locoplan.plan import trunk_kernels
from locoplan.plan.profiles import cruise
from locoplan.plan.tasks import PlannedTask

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True, eq=False)
class TrunkReference:
    """Trunk reference at n times, world frame.

    position (n, 3) m (z = the plan's base height), velocity (n, 3) m/s, acceleration (n, 3)
    m/s^2, yaw (n,) rad (continuous, not wrapped), yaw_rate (n,) rad/s, yaw_acceleration (n,)
    rad/s^2.
    """

    position: FloatArray
    velocity: FloatArray
    acceleration: FloatArray
    yaw: FloatArray
    yaw_rate: FloatArray
    yaw_acceleration: FloatArray


@dataclass(frozen=True, slots=True, eq=False)
class TrunkState:
    """Trunk reference at one time: position (3,) m, velocity (3,) m/s, world frame; yaw rad,
    yaw_rate rad/s."""

    position: FloatArray
    velocity: FloatArray
    yaw: float
    yaw_rate: float


@dataclass(frozen=True, slots=True)
class TrunkSegment:
    """One walk/turn: from (x0, y0, yaw0) at t0 to (x0 + dx, y0 + dy, yaw0 + dyaw) at t1,
    along the cruise blend."""

    task_index: int
    t0: float
    t1: float
    x0: float
    y0: float
    yaw0: float
    dx: float
    dy: float
    dyaw: float


@dataclass(frozen=True, slots=True, eq=False)
class TrunkPath:
    """Piecewise cruise-profile trunk path. `segments` sorted by time; arrays carry a leading
    sentinel (the initial pose, t0 = -inf) for vectorised lookup."""

    height: float
    x_start: float
    y_start: float
    yaw_start: float
    segments: tuple[TrunkSegment, ...]
    _t0: FloatArray
    _dur: FloatArray
    _p0: FloatArray
    _dp: FloatArray
    _yaw0: FloatArray
    _dyaw: FloatArray
    _t0_list: list[float]

    def evaluate(self, times: npt.ArrayLike) -> TrunkReference:
        """Vectorised reference at `times` (n,) s (compiled: `trunk_kernels.evaluate`)."""
        t = np.ascontiguousarray(times, dtype=np.float64).reshape(-1)
        pos, vel, acc, yaw, rate, yaw_acc = trunk_kernels.evaluate(
            t, self._t0, self._dur, self._p0, self._dp, self._yaw0, self._dyaw, self.height
        )
        return TrunkReference(
            position=pos,
            velocity=vel,
            acceleration=acc,
            yaw=yaw,
            yaw_rate=rate,
            yaw_acceleration=yaw_acc,
        )

    def pose_at(self, t: float) -> tuple[float, float, float, float, float, float]:
        """Scalar fast path: (x, y, yaw, vx, vy, yaw_rate) at time t (m, rad, m/s, rad/s)."""
        k = bisect.bisect_right(self._t0_list, t) - 1
        if k < 0:
            return self.x_start, self.y_start, self.yaw_start, 0.0, 0.0, 0.0
        g = self.segments[k]
        dur = g.t1 - g.t0
        s, ds, _ = cruise((t - g.t0) / dur)
        r = ds / dur
        return (
            g.x0 + s * g.dx,
            g.y0 + s * g.dy,
            g.yaw0 + s * g.dyaw,
            r * g.dx,
            r * g.dy,
            r * g.dyaw,
        )

    def state_at(self, t: float) -> TrunkState:
        """Scalar reference at time t as a `TrunkState`."""
        x, y, yaw, vx, vy, wz = self.pose_at(t)
        return TrunkState(np.array([x, y, self.height]), np.array([vx, vy, 0.0]), yaw, wz)

    def end_pose(self) -> tuple[float, float, float]:
        """Final (x, y, yaw) after every locomotion task (m, rad)."""
        if not self.segments:
            return self.x_start, self.y_start, self.yaw_start
        g = self.segments[-1]
        return g.x0 + g.dx, g.y0 + g.dy, g.yaw0 + g.dyaw


def build_trunk_path(
    tasks: tuple[PlannedTask, ...],
    x0: float,
    y0: float,
    yaw0: float,
    height: float,
) -> TrunkPath:
    """Trunk path from the (sorted, non-overlapping) locomotion tasks and the initial pose."""
    segments: list[TrunkSegment] = []
    x, y, yaw = x0, y0, yaw0
    for task in tasks:
        if task.action == "walk" and task.distance is not None:
            c, s = math.cos(yaw), math.sin(yaw)
            bx, by = task.distance
            dx, dy = c * bx - s * by, s * bx + c * by
            turn = task.angle or 0.0
            segments.append(TrunkSegment(task.index, task.start, task.end, x, y, yaw, dx, dy, turn))
            x, y, yaw = x + dx, y + dy, yaw + turn
        elif task.action == "turn" and task.angle is not None:
            segments.append(
                TrunkSegment(task.index, task.start, task.end, x, y, yaw, 0.0, 0.0, task.angle)
            )
            yaw = yaw + task.angle
    # Sentinel row 0 holds the initial pose: t0 = -inf makes tau = +inf, clipped to 1, with a
    # zero displacement, so it evaluates to the start pose at rest.
    t0 = np.array([-np.inf] + [g.t0 for g in segments])
    dur = np.array([1.0] + [g.t1 - g.t0 for g in segments])
    p0 = np.array([[x0, y0]] + [[g.x0, g.y0] for g in segments], dtype=float)
    dp = np.array([[0.0, 0.0]] + [[g.dx, g.dy] for g in segments], dtype=float)
    yaw0s = np.array([yaw0] + [g.yaw0 for g in segments])
    dyaw = np.array([0.0] + [g.dyaw for g in segments])
    return TrunkPath(
        height=height,
        x_start=x0,
        y_start=y0,
        yaw_start=yaw0,
        segments=tuple(segments),
        _t0=t0,
        _dur=dur,
        _p0=p0,
        _dp=dp,
        _yaw0=yaw0s,
        _dyaw=dyaw,
        _t0_list=[g.t0 for g in segments],
    )
