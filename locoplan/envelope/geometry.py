"""Plane geometry of generated scenes: footprints as yawed rectangles, the robot as a circle.

Used by the generator to keep fixtures apart and off the robot's path, and by its tests to
check the scripts it writes. Pure numpy, no MuJoCo.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

# A point on the floor, (x, y).
Point = Sequence[float] | np.ndarray

# m: radius of the circle around the trunk's vertical axis that the legs and feet occupy
# (HECTOR's hips are 0.094 m apart and a line foot is 0.15 m long; with the swing foot's
# placement this is the disc the stance needs). Nothing may be closer to the planned path.
ROBOT_RADIUS = 0.15

# m: least gap between two fixtures, so that they are distinct bodies in the simulator.
FIXTURE_GAP = 0.01


@dataclass(frozen=True, slots=True)
class Rect:
    """A footprint on the floor: centre (cx, cy), full extents along its own x (`length`) and
    y (`width`), yawed by `yaw_deg` counter-clockwise (a fixture's or box's `size[:2]`)."""

    cx: float
    cy: float
    length: float
    width: float
    yaw_deg: float

    @property
    def axes(self) -> np.ndarray:
        """Unit vectors of the rectangle's own x and y axes, as rows."""
        c, s = math.cos(math.radians(self.yaw_deg)), math.sin(math.radians(self.yaw_deg))
        return np.array([[c, s], [-s, c]])

    @property
    def corners(self) -> np.ndarray:
        """The four corners, (4, 2), counter-clockwise."""
        half = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]]) * [self.length / 2, self.width / 2]
        return np.array([self.cx, self.cy]) + half @ self.axes

    def to_local(self, points: np.ndarray) -> np.ndarray:
        """World points (n, 2) in the rectangle's frame (centre at 0, axes along x, y)."""
        return (np.asarray(points, dtype=float) - [self.cx, self.cy]) @ self.axes.T

    def distance_to_point(self, point: Point) -> float:
        """Distance from a point to the rectangle (0 inside)."""
        local = self.to_local(np.asarray([point]))[0]
        dx = max(abs(local[0]) - self.length / 2, 0.0)
        dy = max(abs(local[1]) - self.width / 2, 0.0)
        return math.hypot(dx, dy)


def _separation(a: Rect, b: Rect) -> float:
    """The largest gap between the projections of `a` and `b` on their four face normals
    (negative when they overlap). Positive means apart by at least that much."""
    ca, cb = a.corners, b.corners
    best = -math.inf
    for axis in np.vstack([a.axes, b.axes]):
        pa, pb = ca @ axis, cb @ axis
        gap = max(pb.min() - pa.max(), pa.min() - pb.max())
        best = max(best, gap)
    return best


def rects_apart(a: Rect, b: Rect, gap: float = 0.0) -> bool:
    """True when some face normal separates `a` and `b` by at least `gap` (conservative: two
    rectangles that only miss each other corner to corner by `gap` may be called too close)."""
    return _separation(a, b) >= gap


def _segment_point_distance(p0: np.ndarray, p1: np.ndarray, q: np.ndarray) -> float:
    d = p1 - p0
    n2 = float(d @ d)
    t = 0.0 if n2 == 0.0 else min(1.0, max(0.0, float((q - p0) @ d) / n2))
    return float(np.linalg.norm(p0 + t * d - q))


def _segment_hits_box(p0: np.ndarray, p1: np.ndarray, hx: float, hy: float) -> bool:
    """Liang-Barsky clip of the segment p0-p1 against the box |x| <= hx, |y| <= hy."""
    t0, t1 = 0.0, 1.0
    d = p1 - p0
    for p, q in ((-d[0], p0[0] + hx), (d[0], hx - p0[0]), (-d[1], p0[1] + hy), (d[1], hy - p0[1])):
        if p == 0.0:
            if q < 0.0:
                return False
            continue
        t = q / p
        if p < 0.0:
            t0 = max(t0, t)
        else:
            t1 = min(t1, t)
        if t0 > t1:
            return False
    return True


def segment_rect_distance(rect: Rect, p0: Point, p1: Point) -> float:
    """Distance between the segment p0-p1 and the rectangle (0 when they touch)."""
    a, b = rect.to_local(np.asarray([p0, p1]))
    hx, hy = rect.length / 2, rect.width / 2
    if _segment_hits_box(a, b, hx, hy):
        return 0.0
    local_corners = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]])
    best = min(rect.distance_to_point(p) for p in (p0, p1))
    for corner in local_corners:
        best = min(best, _segment_point_distance(a, b, corner))
    return best


def path_clearance(rect: Rect, path: Sequence[Point]) -> float:
    """Least distance from the rectangle to the polyline `path` (the trunk's planned
    positions, at least one point)."""
    points = [np.asarray(p, dtype=float) for p in path]
    if len(points) == 1:
        return rect.distance_to_point(points[0])
    return min(segment_rect_distance(rect, a, b) for a, b in itertools.pairwise(points))


def layout_ok(
    fixtures: Sequence[Rect],
    path: Sequence[Point],
    loose: Sequence[Rect] = (),
    gap: float = FIXTURE_GAP,
    robot_radius: float = ROBOT_RADIUS,
) -> bool:
    """True when no two `fixtures` overlap (or come within `gap`), no fixture comes within
    `robot_radius` of the trunk's planned `path`, and no `loose` footprint (objects where
    they start) within `robot_radius` of the path's first point (the robot picks them up
    before moving on). Objects rest on fixtures, so they are not checked against them here:
    the caller places each on its own table and keeps it off the others."""
    for i, a in enumerate(fixtures):
        for b in fixtures[i + 1 :]:
            if not rects_apart(a, b, gap):
                return False
    if any(path_clearance(r, path) < robot_radius for r in fixtures):
        return False
    return all(r.distance_to_point(path[0]) >= robot_radius for r in loose)
