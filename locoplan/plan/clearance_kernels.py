"""Compiled kernels of the hand-path clearance check (numba, `cache=True`).

Why compiled: a hand-path search checks thousands of candidate tracks (`locoplan.plan.
hand_paths`), each at a few hundred samples times five trunk poses against every obstacle
(`locoplan.plan.clearance.track_clearance`). As numpy that was some thirty array calls of a
few microseconds each per candidate, 0.6 ms a check and a third of a plan's compile time on
the envelope's picks; compiled it is the arithmetic alone. Each formula is written as the
scalar `HandTrack.evaluate`, `locoplan.plan.hands` waypoint mapping and `Obstacle.distance`
write it, operation for operation in the same order (no fast-math: no reassociation, no
fused multiply-add), so the results are those of the numpy code they replace bit for bit
(checked on the plans of 100 envelope scripts, every hash unchanged).

Array conventions (float64, C-contiguous):
- waypoint rows (7,): point x y z, velocity x y z, 1.0 for a "trunk" waypoint else 0.0;
- obstacle rows (11,): centre x y z, half extents x y z, cos yaw, sin yaw, drift x y (m/s),
  t_ref (s); `spheres` (k,) flags which rows are spheres (radius: half x).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from numba import njit

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

OBSTACLE_COLUMNS = 11


@njit(cache=True, inline="always")
def _world(
    row: FloatArray, bx: float, by: float, bz: float, c: float, s: float
) -> tuple[float, float, float, float, float, float]:
    """World point and velocity (world axes) of a waypoint row with the trunk at (bx, by,
    bz) yawed by (c, s) = (cos, sin)."""
    px, py, pz = row[0], row[1], row[2]
    ux, uy, uz = row[3], row[4], row[5]
    if row[6] > 0.5:
        rx = c * px - s * py
        ry = s * px + c * py
        return bx + rx, by + ry, bz + pz, c * ux - s * uy, s * ux + c * uy, uz
    return px, py, pz, ux, uy, uz


@njit(cache=True)
def track_points(
    seg_times: FloatArray,
    starts: FloatArray,
    rest: FloatArray,
    ts: FloatArray,
    bx: FloatArray,
    by: FloatArray,
    bz: FloatArray,
    c: FloatArray,
    s: FloatArray,
) -> FloatArray:
    """Hand target positions (n, 3) at the times ts (n,) with the trunk at (bx, by, bz) yawed
    by (c, s) at each: `seg_times` (k, 2) each segment's t0 and t1, `starts` (k, 7) its start
    waypoint, `rest` (k + 1, 7) the initial waypoint then each segment's end. Before the
    first segment and after a segment's end the hand rests at its waypoint; within one it
    follows the quintic Hermite blend of `locoplan.plan.profiles.hermite`."""
    n = ts.shape[0]
    k = seg_times.shape[0]
    out = np.empty((n, 3))
    for j in range(n):
        t = ts[j]
        # The segment started last (searchsorted side="right", minus one).
        i = -1
        while i + 1 < k and seg_times[i + 1, 0] <= t:
            i += 1
        if i < 0 or not t < seg_times[i, 1]:
            p = _world(rest[i + 1], bx[j], by[j], bz[j], c[j], s[j])
            out[j, 0], out[j, 1], out[j, 2] = p[0], p[1], p[2]
            continue
        t0, t1 = seg_times[i, 0], seg_times[i, 1]
        T = t1 - t0
        tau = (t - t0) / T
        p = min(max(tau, 0.0), 1.0)
        p2 = p * p
        p3 = p2 * p
        blend = p3 * (10.0 - 15.0 * p + 6.0 * p2)
        g0 = p - 6.0 * p3 + 8.0 * p3 * p - 3.0 * p3 * p2
        g1 = -4.0 * p3 + 7.0 * p3 * p - 3.0 * p3 * p2
        r = 1.0 - blend
        a = _world(starts[i], bx[j], by[j], bz[j], c[j], s[j])
        b = _world(rest[i + 1], bx[j], by[j], bz[j], c[j], s[j])
        for d in range(3):
            out[j, d] = r * a[d] + blend * b[d] + T * (g0 * a[3 + d] + g1 * b[3 + d])
    return out


@njit(cache=True, inline="always")
def _distance(ob: FloatArray, sphere: bool, x: float, y: float, z: float, t: float) -> float:
    """Signed distance (m) from the point to obstacle row `ob` at time t (s): positive
    outside, minus the penetration depth inside (`Obstacle.distance`)."""
    dt = max(0.0, t - ob[10])
    dx = x - ob[0] - ob[8] * dt
    dy = y - ob[1] - ob[9] * dt
    dz = z - ob[2]
    if sphere:
        return math.sqrt(dx * dx + dy * dy + dz * dz) - ob[3]
    c, s = ob[6], ob[7]
    qx = abs(c * dx + s * dy) - ob[3]
    qy = abs(-s * dx + c * dy) - ob[4]
    qz = abs(dz) - ob[5]
    ox, oy, oz = max(qx, 0.0), max(qy, 0.0), max(qz, 0.0)
    outside = math.sqrt(ox * ox + oy * oy + oz * oz)
    return outside + min(max(max(qx, qy), qz), 0.0)


@njit(cache=True)
def distances(ob: FloatArray, sphere: bool, p: FloatArray, t: FloatArray) -> FloatArray:
    """`_distance` of the points p (n, 3) at the times t (n,)."""
    out = np.empty(p.shape[0])
    for j in range(p.shape[0]):
        out[j] = _distance(ob, sphere, p[j, 0], p[j, 1], p[j, 2], t[j])
    return out


@njit(cache=True)
def sample_gaps(
    points: FloatArray,
    ts: FloatArray,
    m: int,
    obstacles: FloatArray,
    spheres: BoolArray,
    hand_radius: float,
) -> FloatArray:
    """Clearances (size, m, k) of the hand sphere from each of the k obstacles at each of the
    `size` sample times ts, with the trunk turned by each of m yaw offsets: `points` ((2 + m)
    size, 3) the hand at each sample with the trunk as planned, then shifted by the position
    error, then turned by each offset. A sample's clearance is the turned hand's distance
    less the hand radius and less how far the shifted trunk moved the hand."""
    size = ts.shape[0]
    k = obstacles.shape[0]
    gaps = np.empty((size, m, k))
    for i in range(size):
        ex = points[i, 0] - points[size + i, 0]
        ey = points[i, 1] - points[size + i, 1]
        ez = points[i, 2] - points[size + i, 2]
        drift = math.sqrt(ex * ex + ey * ey + ez * ez)
        for j in range(m):
            row = 2 * size + j * size + i
            x, y, z = points[row, 0], points[row, 1], points[row, 2]
            for o in range(k):
                d = _distance(obstacles[o], spheres[o], x, y, z, ts[i])
                gaps[i, j, o] = d - hand_radius - drift
    return gaps


def warm_up() -> None:
    """Compile (or load from the cache) every kernel with the types the planner passes: its
    tables and sample times are cached read-only arrays (`locoplan.plan.clearance`)."""

    def frozen(a: FloatArray) -> FloatArray:
        a.flags.writeable = False
        return a

    t = frozen(np.zeros(3))
    seg_times = frozen(np.array([[0.0, 1.0]]))
    pts = track_points(seg_times, frozen(np.zeros((1, 7))), frozen(np.zeros((2, 7))), t, t, t, t,
                       frozen(np.ones(3)), t)  # fmt: skip
    obs = np.zeros((1, OBSTACLE_COLUMNS))
    obs[0, 3:6] = 0.1
    spheres = np.zeros(1, dtype=np.bool_)
    spheres.flags.writeable = False
    distances(frozen(obs)[0], False, pts, np.zeros(3))
    sample_gaps(pts, t, 1, obs, spheres, 0.03)
