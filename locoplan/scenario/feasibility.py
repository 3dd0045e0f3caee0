"""Feasibility checks that need no simulation: what the robot's legs cannot do and scenes that
cannot exist. Each finding is a `LocatedIssue` whose message starts `infeasible (<reason>):`,
says what was measured, the limit, and what would make the script feasible; the loader reports
them like the format's own errors (file:line:column, exit 2), before anything is simulated.

Every figure of the robot comes from the script's robot (`locoplan.plan.robot_geometry.
PlanGeometry`: robot.yaml's `planner.walk_stride`, `planner.hip_yaw_range_deg`, `foot.toe`,
`stance_width`); the derivations below are HECTOR's, whose figures are the defaults (H1:
stride 0.31 m, hip yaw +-24.6 deg, footprint 0.246 m; docs/robots.md).

Reasons:
- `rate`: a walk faster, or a turn quicker, than the gait can step it. A foot in stance moves
  relative to the hip by the distance the trunk covers in one stance phase, about one gait
  period; the leg (thigh + calf L = 0.44 m, hip about h = 0.40 m above the sole at the nominal
  0.60 m trunk height, shared/robot.md) reaches sqrt(L^2 - h^2) = 0.18 m ahead of or behind
  the hip, so v <= 2 * 0.18 / period is the kinematic bound; half of it, WALK_STRIDE / period,
  is the limit (knee and swing-timing margin). The hip yaw range (+-30 deg) bounds the yaw a
  stance foot takes per cycle likewise: |yaw rate| <= 2 * 30 deg / period.
  The limits apply to the planned peak, not the average: the trunk reference
  (plan/profiles.py `cruise`) ramps its speed up over the first third of the task and down
  over the last, so it peaks at 1.5x the average. Envelope seed 6161, run on min-jerk references
  (peak 1.875x the average): of the 7 scripts with a walk whose 1.5x-average peak exceeds the
  limit, 3 fell; the one turn beyond its limit fell;
  8 of the 100 walks within the limit and 33 of the 214 turns were in scripts that failed,
  mostly for other reasons (drops, loaded turns). A limit on the peak refuses the first group
  up front; it is a kinematic bound, not a guarantee: the lateral walks that fell stay
  failures when lengthened to it (README, Envelope).
- `overlap`: an object inside the robot's footprint at the start (within
  ROBOT_FOOTPRINT_RADIUS = 0.135 m of the start position: toes 0.09 m ahead of the ankles,
  feet 0.1 m either side of the centre line; the envelope's nearest edge is 0.15 m), or an
  object that sits inside a fixture rather than on it (more than OVERLAP_TOLERANCE deep).
  Fixtures may stand where the robot starts: the format page's own example has a conveyor
  reaching to the start position (a fixture's sides are not simulated against the legs,
  whose geoms do not collide with it).
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

from locoplan.plan.constants import HIP_YAW_RANGE, WALK_STRIDE
from locoplan.plan.profiles import least_duration, peak_rate
from locoplan.plan.robot_geometry import HECTOR_GEOMETRY, PlanGeometry
from locoplan.scenario.messages import LocatedIssue
from locoplan.scenario.model import FixtureSpec, ObjectSpec, Scenario, TurnTask, WalkTask

# Interpenetration (m) of an object and a fixture below which the object rests on it.
OVERLAP_TOLERANCE = 0.005


def ceil_time(t: float) -> float:
    """A duration rounded up to 0.01 s (what a script writes), so the advice is feasible;
    the envelope's generator rounds its drawn durations the same way."""
    return math.ceil(t * 100.0 - 1e-6) / 100.0


def walk_speed_limit(period: float, stride: float = WALK_STRIDE) -> float:
    """Peak walk speed (m/s) the legs step at a gait `period` (s): `stride` / period (the
    robot's WALK_STRIDE, m; HECTOR's unless given)."""
    return stride / period


def turn_rate_limit(period: float, hip_yaw_range: float = HIP_YAW_RANGE) -> float:
    """Peak yaw rate (rad/s) the hip yaw range (rad either side; HECTOR's unless given)
    allows at a gait `period` (s)."""
    return 2.0 * hip_yaw_range / period


def _rate_issues(scenario: Scenario, geometry: PlanGeometry) -> list[LocatedIssue]:
    period = scenario.gait.period
    issues: list[LocatedIssue] = []
    v_max = walk_speed_limit(period, geometry.walk_stride)
    w_max = turn_rate_limit(period, geometry.hip_yaw_range)
    hip_yaw_deg = math.degrees(geometry.hip_yaw_range)
    for i, task in enumerate(scenario.tasks):
        if isinstance(task, WalkTask):
            dist = math.hypot(task.distance[0], task.distance[1])
            v = peak_rate(dist, task.duration)
            if v > v_max + 1e-9:
                issues.append(
                    LocatedIssue(
                        ("tasks", i, "duration"),
                        f"infeasible (rate): walk of {dist:.3g} m in {task.duration:g} s peaks "
                        f"at {v:.3g} m/s (1.5x the average: the speed ramps up and down); "
                        f"with a gait period of {period:g} s the legs step at most "
                        f"{v_max:.3g} m/s: give the walk at least "
                        f"{ceil_time(least_duration(dist, v_max)):.2f} s",
                    )
                )
        angle = task.angle if isinstance(task, TurnTask | WalkTask) else None
        if angle is not None:
            amount = math.radians(abs(angle))
            rate = peak_rate(amount, task.duration)
            if rate > w_max + 1e-9:
                need = ceil_time(least_duration(amount, w_max))
                issues.append(
                    LocatedIssue(
                        ("tasks", i, "duration"),
                        f"infeasible (rate): {task.action} by {abs(angle):g} deg in "
                        f"{task.duration:g} s peaks at {math.degrees(rate):.0f} deg/s (1.5x "
                        f"the average: the rate ramps up and down); the hip yaw range "
                        f"(+-{hip_yaw_deg:.3g} deg) allows at most "
                        f"{math.degrees(w_max):.0f} deg/s with a gait "
                        f"period of {period:g} s: give it at least {need:.2f} s",
                    )
                )
    return issues


def _rect_corners(
    cx: float, cy: float, hx: float, hy: float, yaw: float
) -> list[tuple[float, float]]:
    c, s = math.cos(yaw), math.sin(yaw)
    return [
        (cx + c * dx - s * dy, cy + s * dx + c * dy)
        for dx, dy in ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy))
    ]


def _rect_penetration(a: list[tuple[float, float]], b: list[tuple[float, float]]) -> float:
    """Smallest overlap (m) of two convex quadrilaterals along their edge normals (separating
    axis test): <= 0 when they do not overlap."""
    depth = math.inf
    for poly in (a, b):
        for k in range(4):
            x0, y0 = poly[k]
            x1, y1 = poly[(k + 1) % 4]
            nx, ny = y1 - y0, x0 - x1
            n = math.hypot(nx, ny)
            if n < 1e-12:
                continue
            nx, ny = nx / n, ny / n
            pa = [px * nx + py * ny for px, py in a]
            pb = [px * nx + py * ny for px, py in b]
            depth = min(depth, min(max(pa), max(pb)) - max(min(pa), min(pb)))
    return depth


def _object_rect(obj: ObjectSpec) -> list[tuple[float, float]]:
    if obj.shape == "sphere":
        r = obj.size[0]
        return _rect_corners(obj.position[0], obj.position[1], r, r, 0.0)
    return _rect_corners(
        obj.position[0], obj.position[1], obj.size[0] / 2, obj.size[1] / 2, math.radians(obj.yaw)
    )


def _object_z(obj: ObjectSpec) -> tuple[float, float]:
    half = obj.size[0] if obj.shape == "sphere" else obj.size[2] / 2
    return obj.position[2] - half, obj.position[2] + half


def _fixture_rect(fx: FixtureSpec) -> list[tuple[float, float]]:
    return _rect_corners(
        fx.position[0], fx.position[1], fx.size[0] / 2, fx.size[1] / 2, math.radians(fx.yaw)
    )


def _distance_to_rect(
    px: float, py: float, cx: float, cy: float, hx: float, hy: float, yaw: float
) -> float:
    """Distance (m) from a point to a rectangle (centre, half extents, yaw; 0 inside)."""
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = px - cx, py - cy
    du = abs(c * dx + s * dy) - hx
    dv = abs(-s * dx + c * dy) - hy
    return math.hypot(max(du, 0.0), max(dv, 0.0))


def _overlap_issues(scenario: Scenario, geometry: PlanGeometry) -> list[LocatedIssue]:
    issues: list[LocatedIssue] = []
    sx, sy = scenario.robot_start.position
    r = geometry.footprint_radius
    for name, obj in scenario.objects.items():
        rect = _object_rect(obj)
        if obj.shape == "sphere":
            hx = hy = obj.size[0]
        else:
            hx, hy = obj.size[0] / 2, obj.size[1] / 2
        d = _distance_to_rect(
            sx, sy, obj.position[0], obj.position[1], hx, hy, math.radians(obj.yaw)
        )
        if d < r:
            issues.append(
                LocatedIssue(
                    ("objects", name, "position"),
                    f"infeasible (overlap): object '{name}' comes within {d:.3f} m of the "
                    f"robot's start position, inside its body; the robot needs {r:.3f} m: "
                    f"move it at least {r - d + 0.001:.3f} m further away",
                )
            )
        bottom, top = _object_z(obj)
        for fname, fx in scenario.fixtures.items():
            depth_z = min(top, fx.size[2]) - max(bottom, 0.0)
            depth_xy = _rect_penetration(rect, _fixture_rect(fx))
            depth = min(depth_z, depth_xy)
            if depth > OVERLAP_TOLERANCE:
                issues.append(
                    LocatedIssue(
                        ("objects", name, "position"),
                        f"infeasible (overlap): object '{name}' sits {depth:.3f} m inside "
                        f"fixture '{fname}' (top at {fx.size[2]:g} m); an object resting on "
                        f"it has its centre at z = {fx.size[2] + (top - bottom) / 2:.3f} m",
                    )
                )
    return issues


def check_feasibility(
    scenario: Scenario, geometry: PlanGeometry = HECTOR_GEOMETRY
) -> list[LocatedIssue]:
    """Every infeasibility of `scenario` found without simulating (module docstring), for
    the robot whose figures `geometry` holds (its walk stride, hip yaw range and footprint;
    HECTOR's by default; the loader passes the script's robot's, `robot_geometry`)."""
    return _rate_issues(scenario, geometry) + _overlap_issues(scenario, geometry)


def robot_geometry(robot: str) -> PlanGeometry:
    """The plan figures of the robot `robot` (a name or an absolute robot path), HECTOR's
    when its description does not load (the plan then refuses the script at its `robot`,
    with the loader's message). Descriptions are loaded once per robot file per process."""
    from locoplan.exceptions import RobotDescriptionError
    from locoplan.robot.description import resolve_robot_yaml

    try:
        path = resolve_robot_yaml(robot).resolve()
    except RobotDescriptionError:
        return HECTOR_GEOMETRY
    return _geometry_of(path)


@functools.cache
def _geometry_of(path: Path) -> PlanGeometry:
    from locoplan.exceptions import RobotDescriptionError
    from locoplan.plan.robot_geometry import plan_geometry
    from locoplan.robot.description import load_robot_description

    try:
        return plan_geometry(load_robot_description(path))
    except (RobotDescriptionError, ValueError):
        return HECTOR_GEOMETRY
