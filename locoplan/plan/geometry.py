"""Object and fixture geometry for manipulation planning (pure functions, SI units, radians).

Objects are boxes (full extents sx, sy, sz, yawed about z) or spheres (radius r); fixtures are
yawed boxes standing on the floor with their top at z = size[2] (shared/scenario-format.md).
"""

from __future__ import annotations

import math

from locoplan.plan.constants import APPROACH_MIN_DISTANCE, PLACE_MARGIN
from locoplan.plan.errors import PlanError
from locoplan.scenario.model import FixtureSpec, ObjectSpec

GRAVITY = 9.81


def half_extents(obj: ObjectSpec) -> tuple[float, float, float]:
    """Half extents (m) of the object along its own axes (a sphere: its radius three times)."""
    if obj.shape == "sphere":
        r = obj.size[0]
        return r, r, r
    return obj.size[0] / 2.0, obj.size[1] / 2.0, obj.size[2] / 2.0


def support_half_width(obj: ObjectSpec, obj_yaw: float, ux: float, uy: float) -> float:
    """Half width (m) of the object's footprint along the horizontal unit vector (ux, uy)."""
    hx, hy, _ = half_extents(obj)
    if obj.shape == "sphere":
        return hx
    c, s = math.cos(obj_yaw), math.sin(obj_yaw)
    return abs(ux * c + uy * s) * hx + abs(-ux * s + uy * c) * hy


def approach_direction(
    from_x: float, from_y: float, to_x: float, to_y: float, heading: float
) -> tuple[float, float]:
    """Horizontal unit vector from a point to another; the heading (rad) when they coincide."""
    dx, dy = to_x - from_x, to_y - from_y
    n = math.hypot(dx, dy)
    if n < APPROACH_MIN_DISTANCE:
        return math.cos(heading), math.sin(heading)
    return dx / n, dy / n


def place_on_fixture(
    fixture_name: str,
    fixture: FixtureSpec,
    obj: ObjectSpec,
    yaw_in_grasp: float,
    robot_x: float,
    robot_y: float,
    robot_yaw: float,
    task_index: int,
    iterations: int = 4,
    travel: float = 0.0,
) -> tuple[tuple[float, float, float], float]:
    """Where to put the object's centre on the fixture's top: (x, y, z) world (m) and the
    object's yaw there (rad).

    The object is placed with its grasp axis across the approach direction (robot to target),
    so its yaw is approach yaw + `yaw_in_grasp`. Its footprint, grown by PLACE_MARGIN, must lie
    inside the top; among those centres the one nearest the robot's planned position is
    taken. Because the yaw depends on the target and the target on the footprint, a few
    fixed-point iterations are run, starting from the fixture's centre.

    `travel` (m, signed along the fixture's own x axis) is how far a conveyor's belt carries
    the object after the release until the run ends: the centre is then chosen among those
    from which it is still supported after that travel (nearest the robot), so that what is
    put on a belt is on the belt at the end; a belt too short for that takes it at its
    upstream end.
    """
    fx, fy = fixture.position[0], fixture.position[1]
    fyaw = math.radians(fixture.yaw)
    fc, fs = math.cos(fyaw), math.sin(fyaw)
    hx_obj, hy_obj, hz_obj = half_extents(obj)
    tx, ty = fx, fy
    obj_yaw = robot_yaw
    for _ in range(iterations):
        ax_, ay_ = approach_direction(robot_x, robot_y, tx, ty, robot_yaw)
        obj_yaw = math.atan2(ay_, ax_) + yaw_in_grasp
        d = obj_yaw - fyaw
        cd, sd = abs(math.cos(d)), abs(math.sin(d))
        if obj.shape == "sphere":
            ex, ey = hx_obj, hy_obj
        else:
            ex, ey = cd * hx_obj + sd * hy_obj, sd * hx_obj + cd * hy_obj
        lim_x = fixture.size[0] / 2.0 - PLACE_MARGIN - ex
        lim_y = fixture.size[1] / 2.0 - PLACE_MARGIN - ey
        if lim_x < 0.0 or lim_y < 0.0:
            raise PlanError(
                f"the object (footprint {2 * ex:.3f} x {2 * ey:.3f} m) does not fit on the top "
                f"of '{fixture_name}' ({fixture.size[0]:g} x {fixture.size[1]:g} m) with a "
                f"{PLACE_MARGIN:g} m margin",
                task_index,
            )
        # Robot position in the fixture frame, clamped into the allowed rectangle.
        rx, ry = robot_x - fx, robot_y - fy
        lo_x, hi_x = -lim_x, lim_x
        if travel > 0.0:
            hi_x = max(lo_x, lim_x - travel)
        elif travel < 0.0:
            lo_x = min(hi_x, -lim_x - travel)
        u = min(max(fc * rx + fs * ry, lo_x), hi_x)
        v = min(max(-fs * rx + fc * ry, -lim_y), lim_y)
        tx, ty = fx + fc * u - fs * v, fy + fs * u + fc * v
    ax_, ay_ = approach_direction(robot_x, robot_y, tx, ty, robot_yaw)
    obj_yaw = math.atan2(ay_, ax_) + yaw_in_grasp
    return (tx, ty, fixture.top_height + hz_obj), obj_yaw


def ballistic_landing(
    p: tuple[float, float, float], v: tuple[float, float, float], rest_height: float
) -> tuple[float, float, float]:
    """Where a point released at p (m) with velocity v (m/s) comes down to z = rest_height,
    ignoring drag and any fixture in the way (m, world). Released below it: p itself."""
    drop = p[2] - rest_height
    if drop < 0.0:
        return p
    t = (v[2] + math.sqrt(v[2] * v[2] + 2.0 * GRAVITY * drop)) / GRAVITY
    return (p[0] + v[0] * t, p[1] + v[1] * t, rest_height)
