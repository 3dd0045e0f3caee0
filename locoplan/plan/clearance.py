"""Clearance of planned hand paths from the scene (pure functions, SI units, radians).

Hands are spheres of the robot's hand radius (HECTOR's HAND_RADIUS by default) around the
hand point; objects (boxes, spheres) and
fixtures (boxes from the floor up to their top) are obstacles. The clearance of a hand at a
point is its sphere's distance to the nearest obstacle surface (negative when it overlaps).

A hand track is checked along the planned trunk path and, because the real trunk follows the
planned yaw only within a few degrees during a turn, also with the yaw off by
+-max(YAW_ERROR_MIN, YAW_LAG_TIME |yaw rate|): "trunk" waypoints swing with the yaw error,
"world" ones stay put. Likewise the trunk may be TRUNK_POSITION_ERROR off its planned position
(it leans back against a load, drifts while stepping), which moves "trunk" waypoints by as much.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from locoplan.plan import clearance_kernels as kernels
from locoplan.plan import constants as k
from locoplan.plan.geometry import half_extents
from locoplan.plan.hands import BasePose, HandTrack, HandWaypoint, Vec3
from locoplan.plan.trunk import TrunkPath
from locoplan.scenario.model import FixtureSpec, ObjectSpec

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class Obstacle:
    """A box (half extents `half` along its own axes, yawed by `yaw` rad about z) or a sphere
    (radius half[0]) centred at `center` (m, world) at time `t_ref` (s), drifting horizontally
    at `drift` (m/s, world; an object riding a conveyor belt) from then on. `name` says what it
    is ("object:box", "fixture:table")."""

    name: str
    center: Vec3
    half: Vec3
    yaw: float = 0.0
    sphere: bool = False
    drift: tuple[float, float] = (0.0, 0.0)
    t_ref: float = 0.0

    def distance(self, p: Vec3, t: float) -> float:
        """Signed distance (m) from the point p (world) to the surface at time t (s):
        positive outside, minus the penetration depth inside."""
        dt = max(0.0, t - self.t_ref)
        dx = p[0] - self.center[0] - self.drift[0] * dt
        dy = p[1] - self.center[1] - self.drift[1] * dt
        dz = p[2] - self.center[2]
        if self.sphere:
            return math.sqrt(dx * dx + dy * dy + dz * dz) - self.half[0]
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        qx = abs(c * dx + s * dy) - self.half[0]
        qy = abs(-s * dx + c * dy) - self.half[1]
        qz = abs(dz) - self.half[2]
        ox, oy, oz = max(qx, 0.0), max(qy, 0.0), max(qz, 0.0)
        outside = math.sqrt(ox * ox + oy * oy + oz * oz)
        return outside + min(max(qx, qy, qz), 0.0)

    def distances(self, p: FloatArray, t: FloatArray) -> FloatArray:
        """`distance` of the points p (n, 3) at the times t (n,), vectorised (compiled:
        `clearance_kernels.distances`)."""
        table, spheres = _obstacle_table((self,))
        return kernels.distances(
            table[0], bool(spheres[0]), np.ascontiguousarray(p, dtype=float),
            np.ascontiguousarray(t, dtype=float),
        )  # fmt: skip


@functools.lru_cache(maxsize=256)
def _obstacle_table(obstacles: tuple[Obstacle, ...]) -> tuple[FloatArray, npt.NDArray[np.bool_]]:
    """The obstacles as `clearance_kernels` rows (k, 11) and sphere flags (k,); cached (a
    search checks every candidate path against the same obstacles), read-only."""
    table = np.array(
        [
            (*ob.center, *ob.half, math.cos(ob.yaw), math.sin(ob.yaw), *ob.drift, ob.t_ref)
            for ob in obstacles
        ],
        dtype=float,
    ).reshape(len(obstacles), kernels.OBSTACLE_COLUMNS)
    spheres = np.array([ob.sphere for ob in obstacles], dtype=np.bool_)
    table.flags.writeable = False
    spheres.flags.writeable = False
    return table, spheres


def object_obstacle(
    name: str,
    obj: ObjectSpec,
    center: Vec3,
    yaw: float,
    drift: tuple[float, float] = (0.0, 0.0),
    t_ref: float = 0.0,
) -> Obstacle:
    """The object `name` resting with its centre at `center` (m) and yaw `yaw` (rad)."""
    return Obstacle(
        f"object:{name}", center, half_extents(obj), yaw, obj.shape == "sphere", drift, t_ref
    )


def fixture_obstacle(name: str, fixture: FixtureSpec) -> Obstacle:
    """The fixture `name` as a solid box from the floor to its top."""
    sx, sy, sz = fixture.size[0], fixture.size[1], fixture.size[2]
    return Obstacle(
        f"fixture:{name}",
        (fixture.position[0], fixture.position[1], sz / 2.0),
        (sx / 2.0, sy / 2.0, sz / 2.0),
        math.radians(fixture.yaw),
    )


def base_pose(trunk: TrunkPath, t: float, yaw_offset: float = 0.0) -> BasePose:
    """The planned trunk pose at t (s) as a `BasePose`, its yaw turned by `yaw_offset` (rad)."""
    x, y, yaw, vx, vy, wz = trunk.pose_at(t)
    yaw += yaw_offset
    return BasePose(x, y, trunk.height, math.cos(yaw), math.sin(yaw), vx, vy, 0.0, wz)


@dataclass(frozen=True, slots=True)
class Clearance:
    """Smallest hand clearance (m) over a checked window, when (s) and from what, and the
    first time (s) the clearance fell below the threshold asked for (None: never).
    `by_obstacle`: the smallest clearance (m) from each obstacle checked, in their order
    (each only over the samples taken when the check gave up early)."""

    minimum: float
    time: float
    obstacle: str
    first_below: float | None
    by_obstacle: tuple[float, ...] = ()

    def better_than(self, other: Clearance) -> bool:
        """Whether this path keeps clearer of the scene than `other`'s (both checked against
        the same obstacles): the larger smallest clearance, and where those are within
        CLEARANCE_TIE the larger next-smallest, and so on (the per-obstacle minima compared
        in increasing order). An obstacle that every candidate path comes as close to (the
        tucked hands sweeping past the near edge of a high conveyor as the trunk turns) then
        does not hide what else a path runs into: H1 envelope seed 48027, transfer-033, took
        a reach that went 3 cm into the parcel it was about to grasp, because every candidate
        came 3.1 cm inside the conveyor's margin first; the pushed parcel slid 3.7 cm, the
        grasp closed 4.2 cm wide and the parcel fell off its target."""
        mine, theirs = sorted(self.by_obstacle), sorted(other.by_obstacle)
        for a, b in zip(mine, theirs, strict=False):
            if abs(a - b) > k.CLEARANCE_TIE:
                return a > b
        return False


def track_clearance(
    track: HandTrack,
    trunk: TrunkPath,
    obstacles: tuple[Obstacle, ...],
    t0: float,
    t1: float,
    threshold: float | tuple[float, ...],
    yaw_offsets: tuple[float, ...] | None = None,
    dt: float = k.CLEARANCE_DT,
    hand_radius: float = k.HAND_RADIUS,
) -> Clearance:
    """Clearance of the hand sphere (radius `hand_radius`, m) following `track` on [t0, t1] (s),
    sampled every `dt` (and at t1; coarser where that would take more than MAX_CLEARANCE_SAMPLES),
    with the trunk on its planned path turned by each of `yaw_offsets` (rad; None: 0 and +-the
    expected yaw error, see the module docstring). The hand point moves at most about 2 m/s, so 10
    ms samples miss at most 2 cm of a path that grazes an edge; thresholds are chosen with that in
    mind. `threshold` (m) is one for every obstacle or one per obstacle (in the order of
    `obstacles`). Every sample is evaluated at once (`trunk_poses` with numpy, the hand and
    the obstacles' distances compiled: `clearance_kernels`): a search checks thousands of
    candidate paths (H1 envelope seed 48027, transfer-004: 4368), which one sample at a time
    took 60 s for one plan."""
    if not obstacles or t1 < t0:
        return Clearance(math.inf, t0, "", None, (math.inf,) * len(obstacles))
    limits = np.array(
        threshold if isinstance(threshold, tuple) else (threshold,) * len(obstacles), dtype=float
    )
    smp = _trunk_samples(trunk, t0, t1, yaw_offsets, dt)
    ts, m = smp.ts, smp.m
    p_all = track_positions(track, smp.t_poses, smp.x, smp.y, smp.z, smp.c, smp.s)
    table, spheres = _obstacle_table(obstacles)
    gaps = kernels.sample_gaps(p_all, ts, m, table, spheres, hand_radius)
    flat = gaps.reshape(ts.size, -1)
    sample_min = flat.min(axis=1)
    nearest = gaps.min(axis=(0, 1))
    below: npt.NDArray[np.bool_] = np.asarray((gaps < limits).any(axis=(1, 2)))
    minimum = float(sample_min.min())
    at = int(np.argmax(sample_min == minimum)) if math.isfinite(minimum) else 0
    what = obstacles[int(flat[at].argmin()) % len(obstacles)].name if math.isfinite(minimum) else ""
    when = float(ts[at]) if math.isfinite(minimum) else t0
    hit = ts[below]
    first: float | None = float(hit.min()) if hit.size else None
    return Clearance(minimum, when, what, first, tuple(nearest.tolist()))


class _TrunkSamples(NamedTuple):
    """See `_trunk_samples`."""

    ts: FloatArray
    m: int
    t_turned: FloatArray
    t_poses: FloatArray
    x: FloatArray
    y: FloatArray
    z: FloatArray
    c: FloatArray
    s: FloatArray


@functools.lru_cache(maxsize=64)
def _trunk_samples(
    trunk: TrunkPath,
    t0: float,
    t1: float,
    yaw_offsets: tuple[float, ...] | None,
    dt: float,
) -> _TrunkSamples:
    """`track_clearance`'s sample times ts (latest first), the number m of yaw offsets, the
    times of the turned poses (m ts.size,), and the times and trunk poses the track is
    evaluated at (t, x, y, z, cos yaw, sin yaw; (2 + m) ts.size each: planned, shifted by
    TRUNK_POSITION_ERROR, then each yaw offset). They depend on the trunk path and the window
    only, and a hand-path search checks hundreds of candidate tracks over one window
    (`hand_paths.approach_segments`): cached (TrunkPath hashes by identity), read-only."""
    n = min(max(1, math.ceil((t1 - t0) / dt - 1e-9)), k.MAX_CLEARANCE_SAMPLES)
    dt = max(dt, (t1 - t0) / n)
    # The samples latest first (the order they were once checked in one by one): of equally near
    # samples, the first in this order names the time and obstacle of the minimum.
    order = np.arange(n, -1, -1)
    ts = np.minimum(t1, t0 + order * dt)
    x, y, yaw, wz = trunk_poses(trunk, ts)
    z = np.full_like(ts, trunk.height)
    if yaw_offsets is None:
        lag = np.maximum(k.YAW_ERROR_MIN, k.YAW_LAG_TIME * np.abs(wz))
        offsets = np.stack((np.zeros_like(lag), -lag, lag), axis=1)
    else:
        offsets = np.broadcast_to(np.asarray(yaw_offsets, dtype=float), (ts.size, len(yaw_offsets)))
    # A trunk TRUNK_POSITION_ERROR off its plan moves trunk-relative targets with it (a
    # blend of trunk and world waypoints partly): the clearance is reduced by that much.
    # One evaluation of the track for every pose: planned, shifted, then each yaw offset.
    m = offsets.shape[1]
    yaws = np.concatenate((yaw, yaw, *(yaw + offsets[:, j] for j in range(m))))
    xs = np.concatenate((x, x + k.TRUNK_POSITION_ERROR, *(x for _ in range(m))))
    reps = 2 + m
    out = (
        ts,
        np.tile(ts, m),
        np.tile(ts, reps),
        xs,
        np.tile(y, reps),
        np.tile(z, reps),
        np.cos(yaws),
        np.sin(yaws),
    )
    for a in out:
        a.flags.writeable = False
    return _TrunkSamples(out[0], m, *out[1:])


def trunk_poses(
    trunk: TrunkPath, ts: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """`TrunkPath.pose_at` at the times ts (n,): x, y, yaw and yaw rate (m, rad, rad/s), from
    the path's own vectorised `TrunkPath.evaluate` (the same arithmetic)."""
    ref = trunk.evaluate(ts)
    return ref.position[:, 0], ref.position[:, 1], ref.yaw, ref.yaw_rate


def _waypoint_table(ws: list[HandWaypoint]) -> FloatArray:
    """Rows (point x y z, velocity x y z, 1 for "trunk" else 0) of the waypoints `ws`."""
    return np.array([(*w.point, *w.velocity, 1.0 if w.frame == "trunk" else 0.0) for w in ws])


def track_positions(
    track: HandTrack,
    ts: FloatArray,
    bx: FloatArray,
    by: FloatArray,
    bz: FloatArray,
    c: FloatArray,
    s: FloatArray,
) -> FloatArray:
    """`HandTrack.evaluate`'s positions (n, 3) at the times ts (n,) with the trunk at (bx, by,
    bz) yawed by (c, s) = (cos, sin) at each, vectorised, each computed as `evaluate`
    computes it."""
    seg_times, starts, rest = _track_tables(track)
    return kernels.track_points(seg_times, starts, rest, ts, bx, by, bz, c, s)


@functools.lru_cache(maxsize=256)
def _track_tables(track: HandTrack) -> tuple[FloatArray, FloatArray, FloatArray]:
    """`clearance_kernels.track_points`' tables of a track: each segment's (t0, t1) (k, 2),
    its start waypoint row (k, 7), and the initial waypoint then each segment's end (k + 1,
    7); cached (HandTrack hashes by identity), read-only."""
    segs = track.segments
    seg_times = np.array([(g.t0, g.t1) for g in segs], dtype=float).reshape(len(segs), 2)
    starts = _waypoint_table([g.start for g in segs]).reshape(len(segs), 7)
    rest = _waypoint_table([track.initial, *(g.end for g in segs)])
    for a in (seg_times, starts, rest):
        a.flags.writeable = False
    return seg_times, starts, rest
