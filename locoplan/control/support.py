"""The support region of line feet on the ground and the nearest point inside it.

Each foot is a segment along its yaw, from `heel` behind to `toe` ahead of its sole point
(robot.yaml); the support region is the convex hull of the segments (a quadrilateral in
double support). `clamp_into_support` moves a horizontal point into that hull shrunk by a
margin, to the nearest point, by enumerating the active sets of the (at most four)
half-planes: a least-distance problem this small needs no QP solver.
"""

from __future__ import annotations

import itertools

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


def foot_segments(p_feet: FloatArray, yaw_feet: FloatArray, toe: float, heel: float) -> FloatArray:
    """End points (2 n, 2) of the line feet at p_feet (n, >=2) m with yaws (n,) rad."""
    pts = []
    feet = np.asarray(p_feet, dtype=float)
    for p, yaw in zip(feet, np.asarray(yaw_feet, dtype=float), strict=True):
        u = np.array([np.cos(yaw), np.sin(yaw)])
        pts.append(p[:2] + toe * u)
        pts.append(p[:2] - heel * u)
    return np.array(pts)


def convex_hull(points: FloatArray) -> FloatArray:
    """Vertices (m, 2) of the convex hull of points (n, 2), counter-clockwise (monotone chain;
    collinear points dropped)."""
    pts = sorted({(float(x), float(y)) for x, y in np.asarray(points, dtype=float)})
    if len(pts) <= 2:
        return np.array(pts)

    def cross(o: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list[tuple[float, float]] = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0.0:
            lower.pop()
        lower.append(p)
    upper: list[tuple[float, float]] = []
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0.0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


# The last polygon `_half_planes` was asked for and its half-planes: an MPC update asks for
# the same feet's polygon up to three times (`clamp_into_support`, `chord_offsets` for the
# held-load lean and for the pre-lift lean), 25 us each.
_LAST_PLANES: list[tuple[bytes, FloatArray, FloatArray]] = []


def _half_planes(hull: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The convex polygon `hull` (m, 2, CCW) as half-planes n . x <= c: unit outward normals
    (m, 2), one per edge from vertex i to i + 1, and their offsets c (m,). Read-only arrays
    (shared with the next call for the same polygon)."""
    hull = np.asarray(hull, dtype=float)
    key = hull.tobytes() + bytes(str(hull.shape), "ascii")
    last = _LAST_PLANES[0] if _LAST_PLANES else None  # one read: another thread may replace it
    if last is not None and last[0] == key:
        return last[1], last[2]
    edges = np.concatenate((hull[1:], hull[:1])) - hull
    normals = np.empty_like(edges)  # outward for a CCW polygon
    normals[:, 0] = edges[:, 1]
    normals[:, 1] = -edges[:, 0]
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    offsets = np.einsum("ij,ij->i", normals, hull)
    normals.flags.writeable = False
    offsets.flags.writeable = False
    _LAST_PLANES[:] = [(key, normals, offsets)]
    return normals, offsets


def clamp_into_support(p: FloatArray, hull: FloatArray, margin: float) -> FloatArray:
    """The point (2,) nearest to p (2,) inside the convex polygon `hull` (m, 2, CCW) shrunk by
    `margin` m; p itself when it is inside. Where the shrunk polygon is empty (the feet too
    close for the margin) or the hull has fewer than three vertices: the hull's centroid."""
    p = np.asarray(p, dtype=float)
    m = len(hull)
    if m < 3:
        return np.asarray(hull, dtype=float).mean(axis=0) if m else p
    normals, offsets = _half_planes(hull)
    offsets = offsets - margin  # n . x <= offset inside, shrunk
    tol = 1e-12
    if np.all(normals.dot(p) <= offsets + tol):
        return p
    best: FloatArray | None = None
    best_d = np.inf
    candidates = []
    for i in range(m):  # one active half-plane: project onto its line
        candidates.append(p - (normals[i].dot(p) - offsets[i]) * normals[i])
    for i, j in itertools.combinations(range(m), 2):  # two: their lines' intersection
        a = np.array([normals[i], normals[j]])
        if abs(np.linalg.det(a)) > 1e-12:
            candidates.append(np.linalg.solve(a, np.array([offsets[i], offsets[j]])))
    for c in candidates:
        if np.all(normals.dot(c) <= offsets + 1e-9):
            d = float(np.linalg.norm(c - p))
            if d < best_d:
                best, best_d = c, d
    return best if best is not None else np.asarray(hull, dtype=float).mean(axis=0)


def share_between_feet(p: FloatArray, c0: FloatArray, c1: FloatArray, share: float) -> FloatArray:
    """p (2,) moved along the line from the foot centre c0 (2,) to c1 (2,) so that its
    projection lies at least `share` of their distance from each (lever rule: each of two
    feet then carries at least about `share` of a static weight at p); p itself when it does."""
    d = np.asarray(c1, dtype=float) - np.asarray(c0, dtype=float)
    gap = float(np.hypot(d[0], d[1]))
    if gap < 1e-9:
        return np.asarray(p, dtype=float)
    u = d / gap
    lam = float((np.asarray(p) - c0).dot(u)) / gap
    moved = min(max(lam, share), 1.0 - share)
    return np.asarray(p, dtype=float) + (moved - lam) * gap * u


def chord_offsets(p: FloatArray, directions: FloatArray, hull: FloatArray) -> FloatArray:
    """How far (n,) m the point p (2,) stands ahead of the middle of the convex polygon
    `hull` (m, 2, CCW) along each unit direction of `directions` (n, 2): the middle of the
    chord through p along that direction, whose ends are where p + l u leaves the polygon,
    lies at l = (l_back + l_front) / 2, and p stands -(l_back + l_front) / 2 ahead of it.
    NaN where the hull has fewer than three vertices or p lies outside it."""
    u = np.asarray(directions, dtype=float)
    out = np.full(len(u), np.nan)
    m = len(hull)
    if m < 3:
        return out
    p = np.asarray(p, dtype=float)
    normals, offsets = _half_planes(hull)
    room = offsets - normals.dot(p)  # n . (p + l u) <= n . v
    if (room < 0.0).any():
        return out
    nu = u.dot(normals.T)  # (n, m)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = room[None, :] / nu
    front = np.where(nu > 1e-12, lam, np.inf).min(axis=1)
    back = np.where(nu < -1e-12, lam, -np.inf).max(axis=1)
    ok = np.isfinite(front) & np.isfinite(back)
    out[ok] = -0.5 * (front[ok] + back[ok])
    return out
