"""Hand paths of manipulation: poses, the collision-checked approach and retreat, the throw
line (pure functions over the planned trunk path; SI units, radians).

Poses marked "in trunk" are relative to the trunk origin in the trunk's yaw-only frame; the
sign of y flips for the right hand (hand index 0 = left, 1 = right). The robot's figures
(hand poses, hand radius, carry distance, trunk front) come in as a `PlanGeometry` (`geo`,
HECTOR's when not given). Every path that moves a
hand towards or away from an object is checked with `locoplan.plan.clearance` against the
scene along the planned trunk path, so that the hands do not sweep into what the robot turns
or walks towards, nor knock what it has just put down.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from locoplan.plan import constants as k
from locoplan.plan.clearance import Clearance, Obstacle, track_clearance
from locoplan.plan.geometry import GRAVITY, half_extents
from locoplan.plan.hands import HandSegment, HandWaypoint, Vec3, make_track
from locoplan.plan.robot_geometry import HECTOR_GEOMETRY, PlanGeometry
from locoplan.plan.trunk import TrunkPath
from locoplan.scenario.model import ObjectSpec

HAND_NAMES: tuple[str, str] = ("L", "R")
SIDE = (1.0, -1.0)  # +y for the left hand, -y for the right


def default_waypoint(hand: int, geo: PlanGeometry = HECTOR_GEOMETRY) -> HandWaypoint:
    """The default (carry-ready) hand pose in trunk (`geo.hand_default_in_trunk`)."""
    x, y, z = geo.hand_default_in_trunk
    return HandWaypoint((x, SIDE[hand] * y, z), "trunk")


def tuck_waypoint(hand: int, width: float, geo: PlanGeometry = HECTOR_GEOMETRY) -> HandWaypoint:
    """The tucked hand pose in trunk (`geo.hand_tuck_in_trunk`), `width` (m) off the trunk's
    centre line."""
    x, _, z = geo.hand_tuck_in_trunk
    return HandWaypoint((x, SIDE[hand] * width, z), "trunk")


# Peak acceleration of the tracks' rest-to-rest quintic over d (m) in T (s): _QUINTIC_PEAK d / T^2.
_QUINTIC_PEAK = 10.0 / math.sqrt(3.0)


def rest_to_rest_duration(distance: float, accel: float) -> float:
    """Shortest duration (s) of a rest-to-rest hand move over `distance` (m) whose peak
    acceleration, 10 / sqrt(3) d / T^2 for the tracks' quintic, stays within `accel` (m/s^2;
    the robot's `PlanGeometry.hand_accel_limit` for a free move)."""
    return math.sqrt(_QUINTIC_PEAK * max(distance, 0.0) / accel)


def rest_to_rest_distance(duration: float, accel: float) -> float:
    """Farthest (m) a rest-to-rest hand move of `duration` (s) goes with its peak acceleration
    within `accel` (m/s^2): the inverse of `rest_to_rest_duration`."""
    return accel * duration * duration / _QUINTIC_PEAK


def lifted_tuck_waypoint(
    hand: int,
    width: float,
    target: HandWaypoint,
    trunk: TrunkPath,
    geo: PlanGeometry = HECTOR_GEOMETRY,
) -> HandWaypoint:
    """The tucked pose raised to the height of `target` (in trunk: a "trunk" target's own z, a
    "world" target's height above the planned trunk height): close to the body, where nothing
    on a table is, at the height the reach then goes out level."""
    z = target.point[2] if target.frame == "trunk" else target.point[2] - trunk.height
    x, _, _ = geo.hand_tuck_in_trunk
    return HandWaypoint((x, SIDE[hand] * width, z), "trunk")


def initial_waypoint(
    hand: int,
    trunk: TrunkPath,
    obstacles: tuple[Obstacle, ...],
    until: float,
    geo: PlanGeometry = HECTOR_GEOMETRY,
) -> HandWaypoint:
    """Where the hand starts (and rests until its first task): the default pose, unless that
    pose comes within APPROACH_CLEARANCE of an object or fixture on [0, until] (s) along the
    planned trunk path (a box on a table 0.20-0.28 m ahead overlaps hands held 0.28 m ahead;
    turning towards a table sweeps them into it); then the tucked pose, low and within
    0.16 m of the trunk axis (HAND_TUCK_IN_TRUNK; `geo`'s). The simulator starts the arms in
    this pose, so a scene laid out close to the robot is not touched before the plan means
    to."""
    default = default_waypoint(hand, geo)
    idle = make_track(HAND_NAMES[hand], default, [])
    c = track_clearance(
        idle,
        trunk,
        obstacles,
        0.0,
        max(until, 0.0),
        k.APPROACH_CLEARANCE,
        hand_radius=geo.hand_radius,
    )
    if c.first_below is None:
        return default
    return tuck_waypoint(hand, geo.hand_tuck_in_trunk[1], geo)


def grip_height(obj: ObjectSpec, geo: PlanGeometry = HECTOR_GEOMETRY) -> float:
    """How far above its centre (m) a box carried through a walk, turn or steps is gripped:
    GRASP_ABOVE_CENTRE (at most up to HAND_RADIUS + GRASP_TOP_MARGIN below its top). Two point
    contacts leave the box free to turn about the line through them, with nothing to damp it:
    gripped at its centre, one knock (lift-off, a step) sets it turning for good; gripped
    above, it hangs level like a pendulum. Held standing still, the box is gripped at its
    centre (no pendulum for the hands' own motion to excite; this keeps the 14 kg hold within
    its thin torque margins). A sphere is always gripped at its equator."""
    if obj.shape == "sphere":
        return 0.0
    top = half_extents(obj)[2] - geo.hand_radius - k.GRASP_TOP_MARGIN
    return max(0.0, min(k.GRASP_ABOVE_CENTRE, top))


def grip_behind(obj: ObjectSpec, depth: float, geo: PlanGeometry = HECTOR_GEOMETRY) -> float:
    """How far nearer the robot than its centre (m, along the approach) a box of
    `payload.behind_grips` is gripped: GRIP_BEHIND_CENTRE, at most up to the hand radius +
    GRASP_TOP_MARGIN inside its near face, which lies `depth` (m) from its centre towards the
    robot (constants' docstring). A sphere is gripped at its centre."""
    if obj.shape != "box":
        return 0.0
    room = depth - geo.hand_radius - k.GRASP_TOP_MARGIN
    return max(0.0, min(k.GRIP_BEHIND_CENTRE, room))


def carry_forward(
    pose: tuple[float, float, float, float, float, float],
    ox: float,
    oy: float,
    geo: PlanGeometry = HECTOR_GEOMETRY,
) -> float:
    """How far ahead of the trunk (m) a picked object is carried at the pick's end: where it
    was picked (centre (ox, oy), m), seen from the planned trunk `pose` (x, y, yaw, ...) at the
    pick's end, within CARRY_FORWARD (`geo.carry_forward`) +- CARRY_FORWARD_RANGE. Two point grips
    leave the object free to swing about the grip axis (a pendulum with nothing to damp it), so the
    pick does not pull it in horizontally in a hurry; held standing, it settles in to CARRY_FORWARD
    afterwards. (An object carried through locomotion comes in closer, to `carry_in`, during
    the raise: the manipulation planner takes the smaller of the two.)"""
    x, y, yaw = pose[0], pose[1], pose[2]
    ahead = math.cos(yaw) * (ox - x) + math.sin(yaw) * (oy - y)
    lo = geo.carry_forward - k.CARRY_FORWARD_RANGE
    hi = geo.carry_forward + k.CARRY_FORWARD_RANGE
    return min(max(ahead, lo), hi)


def carry_in(depth: float, geo: PlanGeometry = HECTOR_GEOMETRY) -> float:
    """How far ahead of the trunk (m) an object carried through locomotion is held: its near
    face CARRY_IN_GAP from the trunk's front (TRUNK_FRONT, `geo.trunk_front`), for an object
    reaching `depth` (m) from its centre towards the robot (constants' docstring)."""
    return geo.trunk_front + depth + k.CARRY_IN_GAP


def settle_in(
    distance: float,
    available: float,
    accel: float = k.CARRY_SETTLE_ACCEL,
    least: float = k.CARRY_SETTLE_TIME,
) -> tuple[float, float]:
    """(how far, how long): the settling-in move over `distance` (m) in at most `available`
    (s) with a rest-to-rest peak acceleration of `accel` (m/s^2; CARRY_SETTLE_ACCEL for a
    hold standing still, `pull_accel` for one carried through locomotion), taking at least
    `least` (s); when the time is short the move goes only as far as it allows."""
    needed = max(least, rest_to_rest_duration(distance, accel))
    if needed <= available:
        return distance, needed
    return min(distance, rest_to_rest_distance(available, accel)), available


def pull_accel(mass: float, geo: PlanGeometry = HECTOR_GEOMETRY) -> float:
    """Peak acceleration (m/s^2) of a held object of `mass` (kg) pulled in towards the trunk
    (`carry_in`): the arms and the object then push the trunk with (arm_moving_mass + mass) a,
    held to the force hand_accel_limit gives the empty arms (`geo`'s; constants'
    HAND_ACCEL_LIMIT and ARM_MOVING_MASS)."""
    m_arm = geo.arm_moving_mass
    return geo.hand_accel_limit * m_arm / (m_arm + max(mass, 0.0))


def heavy_pull(mass: float, ahead: float, leg_torque: float) -> bool:
    """Whether an object of `mass` (kg) picked `ahead` (m ahead of the trunk) is heavy for
    its pull-in: its weight times that distance exceeds PULL_FAST_SHARE of the weakest leg
    joint's torque limit `leg_torque` (N m; constants' PULL_FAST_SHARE)."""
    return mass * GRAVITY * ahead > k.PULL_FAST_SHARE * leg_torque


def beside(p: Vec3, d: float, lx: float, ly: float) -> Vec3:
    """p moved horizontally by d along the unit vector (lx, ly)."""
    return (p[0] + d * lx, p[1] + d * ly, p[2])


@dataclass(frozen=True, slots=True)
class PreGrasp:
    """Where a hand waits beside an object before closing on it: `offset` (m) of the hand
    point outside the object's side, the hand sphere's `clearance` (m) there from the nearest
    other obstacle, and that obstacle's `obstacle` name ("" when nothing is near)."""

    offset: float
    clearance: float
    obstacle: str


def pregrasp_offset(
    grip: Vec3,
    lateral: tuple[float, float],
    half: float,
    obstacles: tuple[Obstacle, ...],
    t: float,
    geo: PlanGeometry = HECTOR_GEOMETRY,
) -> PreGrasp:
    """Where the hand waits beside an object before closing on it: `grip` (m, world) is the
    grip point on the object's centre line, `lateral` the unit vector (world, horizontal) from
    it towards this hand's side, `half` the object's half width along it; `obstacles` what
    else is there at t (s; not the object itself).

    `geo.grasp_clearance` outside the side (the hand sphere 3 cm off it) unless something else
    stands nearer the sphere there than the side does; then the offset that keeps the sphere
    as far from both as it can (between the side and a platform beside the box: the middle),
    down to PREGRASP_GAP off the side, on a PREGRASP_STEP grid. Why: the nominal point put
    H1's hand 0.4 cm off a platform beside the box or up to 3.2 cm into it (side-carry, seeds
    5021-17021), the hand hit the platform's edge in the reach and the robot fell backwards
    (five of eight runs; those whose hand fits between now pass). Whether the hand fits at all
    (`PreGrasp.clearance` at least PREGRASP_GAP) is the caller's check."""
    lx, ly = lateral
    r = geo.hand_radius

    def clear(d: float) -> tuple[float, str]:
        at = beside(grip, half + d, lx, ly)
        best, name = math.inf, ""
        for ob in obstacles:
            c = ob.distance(at, t) - r
            if c < best:
                best, name = c, ob.name
        return best, name

    nominal = geo.grasp_clearance
    c, name = clear(nominal)
    if c >= nominal - r:
        return PreGrasp(nominal, c, name if math.isfinite(c) else "")
    best = PreGrasp(nominal, c, name)
    least = r + k.PREGRASP_GAP
    n = max(0, int((nominal - least) / k.PREGRASP_STEP + 1e-9))
    for i in range(1, n + 1):
        d = nominal - i * k.PREGRASP_STEP
        c, name = clear(d)
        if min(c, d - r) > min(best.clearance, best.offset - r):
            best = PreGrasp(d, c, name)
    return best


def along(p: Vec3, d: float, u: Vec3) -> Vec3:
    """p moved by d along the unit vector u."""
    return (p[0] + d * u[0], p[1] + d * u[1], p[2] + d * u[2])


def world_to_trunk(trunk: TrunkPath, t: float, p: Vec3) -> Vec3:
    """The world point p (m) in the planned trunk frame at t (s)."""
    x, y, yaw, *_ = trunk.pose_at(t)
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = p[0] - x, p[1] - y
    return (c * dx + s * dy, -s * dx + c * dy, p[2] - trunk.height)


def path_clearance(
    hand: int,
    done: list[HandSegment],
    extra: list[HandSegment],
    t0: float,
    t1: float,
    trunk: TrunkPath,
    obstacles: tuple[Obstacle, ...],
    threshold: float | tuple[float, ...],
    initial: HandWaypoint | None = None,
    geo: PlanGeometry = HECTOR_GEOMETRY,
) -> Clearance:
    """Clearance on [t0, t1] (s) of the hand's track made of the segments `done` so far and
    the candidate segments `extra`, from the `initial` waypoint (default: the default pose)."""
    start = default_waypoint(hand, geo) if initial is None else initial
    track = make_track(HAND_NAMES[hand], start, done + extra)
    return track_clearance(
        track,
        trunk,
        obstacles,
        t0,
        t1,
        threshold,
        hand_radius=geo.hand_radius,
    )


def approach_segments(
    hand: int,
    done: list[HandSegment],
    start: float,
    task_index: int,
    target: HandWaypoint,
    t_end: float,
    tuck_y: float,
    trunk: TrunkPath,
    obstacles: tuple[Obstacle, ...],
    initial: HandWaypoint | None = None,
    geo: PlanGeometry = HECTOR_GEOMETRY,
    entry: HandWaypoint | None = None,
) -> list[HandSegment]:
    """Segments that bring the hand from where `done` leaves it (or from `initial`, default the
    default pose, when nothing is done yet) to `target` at t_end (s).

    Directly (a straight blend from `start`, s) when that keeps APPROACH_CLEARANCE from every
    obstacle along the planned trunk path (with the yaw off by as much as it may be);
    otherwise the hand first tucks in (close to the body and `tuck_y` wide, in trunk; possibly
    before `start`, as soon as the hand is free) before the direct path would collide, waits
    there while the trunk turns or walks, and reaches out at the earliest time from which the
    rest of the path is clear (tucking earlier, down to as soon as the hand is free, when the
    tuck itself would pass too close). A hand that starts closer than APPROACH_CLEARANCE (resting
    beside the object) only has to get no closer (within APPROACH_SLACK).

    If neither is clear, the clearest one wins (the largest smallest clearance, ties within
    CLEARANCE_TIE going to the larger next-smallest: `Clearance.better_than`), unless that one
    runs the hand into something (a negative clearance), or comes within OBJECT_GRAZE of an
    object (not a fixture: a grazed object is pushed), and an `entry` is given (a "world" point
    level with the target, beside the near corner of the object the target is beside): then the
    same paths are tried again going to `entry` first and sliding from there to `target` along
    the object's side ("slide", `_entry_finish`), and the first clear one is taken. Only then
    and only a clear one: an entry path adds a stop and takes time from the reach; tried
    whenever no path was clear, it also replaced HECTOR's near-misses (1.9-2.5 cm from a box,
    against the 2.5 cm asked) in five of the repository's scenarios and 101 of seed 16339's 280
    manipulation runs (98 of them succeeded either way), and tried with entry paths that are not
    clear either, one that came 3.4 cm into a platform instead of 4 cm made a run that had
    placed its parcel fall (seed 16339, quasi-static transfer-007). When no entry path is clear
    either, the clearest of them replaces the best path only if it keeps out of everything
    (clearance >= 0) where the best runs into something: H1's left hand reaching past a
    platform's near corner to a box beside it (side-carry, seed 16021's -016 and 5021's -002)
    went 3.4-3.6 cm into the platform's edge by the straight reach and the robot fell
    backwards; by way of the entry it keeps 0.5-1.8 cm and both place their box. A path that
    only grazes an object is replaced by a clear entry path only.

    When every path still runs into something, the hand goes over the fixtures it comes too
    near, where their tops (plus the hand's radius and margins) are above the target
    (`_over_waypoint`): straight to the point above the target and down onto it, or else
    risen close to the body to that height and out from there, the latest such reach that is
    clear and no faster than the arms' free-move acceleration; only a clear one replaces the
    best path.

    Why the entry: in a pick during a turn, the object sweeps across the trunk frame while the
    hand reaches out, and a straight reach towards the point beside its far side cut through
    its near corner. Unitree H1's envelope (seed 33331): the right hand's best path came 2-5 cm
    inside the parcel (13 of 60 transfers); the hand met the parcel's near face or the
    table's edge under it, the grasp closed with that hand at the parcel's corner or under it,
    and the parcel turned 50-110 deg in the hands (7 of those 13 runs failed: parcels tipped
    or slid off their target, two falls).
    """
    first = default_waypoint(hand, geo) if initial is None else initial
    cur = done[-1].end if done else first
    t_free = done[-1].t1 if done else 0.0

    def gap(
        extra: list[HandSegment],
        t0: float,
        t1: float,
        threshold: float | tuple[float, ...],
        obs: tuple[Obstacle, ...] = obstacles,
    ) -> Clearance:
        return path_clearance(hand, done, extra, t0, t1, trunk, obs, threshold, first, geo)

    def finish(t_r: float, frm: HandWaypoint, via: HandWaypoint | None) -> list[HandSegment]:
        """From `frm` at t_r to the target at t_end: straight, or by way of `via`."""
        if via is None:
            return [HandSegment(t_r, t_end, frm, target, task_index, "reach")]
        return _entry_finish(t_r, t_end, frm, via, target, task_index, geo.hand_accel_limit)

    direct = finish(start, cur, None)
    # Per obstacle: a hand that starts within APPROACH_CLEARANCE of one only has to get no
    # closer to that one. (One threshold for all, lowered by whatever the hand started near,
    # let a reach that started beside the platform cut the table's edge: envelope seed 14142,
    # transfer-002, the right hand blocked 10 cm short of the grasp and the robot fell.)
    threshold = tuple(
        min(
            k.APPROACH_CLEARANCE,
            gap(direct, t_free, t_free, -math.inf, (ob,)).minimum - k.APPROACH_SLACK,
        )
        for ob in obstacles
    )
    c_direct = gap(direct, t_free, t_end, threshold)
    if c_direct.first_below is None:
        return direct
    t_hit = c_direct.first_below

    tuck = tuck_waypoint(hand, tuck_y, geo)
    # A hand that rests tucked already (the initial pose beside a near table, or a retreat's
    # end; in trunk) only widens to this tuck, in the time its arm needs for that, and the
    # rise and reach may begin as soon as the hand is free. (Standing picks from a tucked
    # start had no time for a full 0.4 s tuck as well, kept the straight reach and cut the
    # table's near edge with the hands: envelope seed 11, standing-hold-010 fell backwards.)
    tx, _, tz = geo.hand_tuck_in_trunk
    if cur.frame == "trunk" and abs(cur.point[0] - tx) + abs(cur.point[2] - tz) < 1e-9:
        tuck_time = rest_to_rest_duration(math.dist(cur.point, tuck.point), geo.hand_accel_limit)
    else:
        tuck_time = k.TUCK_DURATION
    # Latest tuck first (the hands stay out as long as they can), then earlier ones; for each,
    # the earliest reach start from which the rest is clear.
    t_tuck1_latest = max(
        min(max(t_hit - k.TUCK_LEAD, t_free + tuck_time), t_end - k.REACH_MIN_DURATION),
        t_free + tuck_time,
    )
    # From the tucked pose (below table tops) the hand first rises close to the body to the
    # target's height, then reaches out level: a straight line from below a table's top to a
    # point above it would cut the table's near edge.
    lifted = lifted_tuck_waypoint(hand, tuck_y, target, trunk, geo)

    def tucked(
        t_tuck0: float, t_tuck1: float, t_r: float, risen: HandWaypoint, via: HandWaypoint | None
    ) -> list[HandSegment]:
        """A tucked path: the tuck on [t_tuck0, t_tuck1] (none for a hand that rests tucked),
        the rise close to the body to `risen` ending at t_r, then `finish` by way of `via`."""
        moves = [HandSegment(t_tuck0, t_tuck1, cur, tuck, task_index, "tuck")] if tuck_time else []
        return [
            *moves,
            HandSegment(t_r - geo.tuck_lift_duration, t_r, tuck, risen, task_index, "lift"),
            *finish(t_r, risen, via),
        ]

    def search(
        via: HandWaypoint | None, best: list[HandSegment], best_c: Clearance, only_clear: bool
    ) -> tuple[bool, list[HandSegment], Clearance]:
        """The tucked paths (tuck, rise close to the body, then `finish` by way of `via` from
        the raised tuck): whether one is clear, that one or the clearest so far (`best`, with
        clearance `best_c`; `Clearance.better_than`), and its clearance. `only_clear`: the first
        clear path is wanted; otherwise only a clear path that is also `better_than` the best so
        far ends the search (the rule of the one-sample-at-a-time check, which gave up on a
        path once it could not be better; plans are as they were with it)."""
        t_tuck1 = t_tuck1_latest
        while True:
            t_tuck0 = max(t_free, t_tuck1 - tuck_time)
            if tuck_time > 0.0 and t_tuck1 <= t_tuck0:
                break
            t_first = t_tuck1 + geo.tuck_lift_duration
            n = int((t_end - k.REACH_MIN_DURATION - t_first) / k.REACH_START_STEP + 1e-9)
            for j in range(n + 1):
                t_r = t_first + j * k.REACH_START_STEP
                cand = tucked(t_tuck0, t_tuck1, t_r, lifted, via)
                c = gap(cand, t_tuck0, t_end, threshold)
                better = not only_clear and c.better_than(best_c)
                if c.first_below is None and (only_clear or better):
                    return True, cand, c
                if better:
                    best, best_c = cand, c
            if t_tuck0 <= t_free:
                break
            t_tuck1 = max(t_tuck1 - k.TUCK_STEP, t_free + tuck_time)
        return False, best, best_c

    found, best, best_c = search(None, direct, c_direct, only_clear=False)
    grazes = any(
        ob.name.startswith("object:") and near < k.OBJECT_GRAZE
        for ob, near in zip(obstacles, best_c.by_obstacle, strict=True)
    )
    if found or (best_c.minimum >= 0.0 and not grazes):
        return best
    if entry is not None:
        # By way of the entry: only a clear path replaces the best one.
        cand = finish(start, cur, entry)
        c_cand = gap(cand, t_free, t_end, threshold)
        if c_cand.first_below is None:
            return cand
        found, via_entry, _ = search(entry, best, best_c, only_clear=True)
        if found:
            return via_entry
        # No path is clear either way: the clearest entry path, if it keeps out of
        # everything while the best of the others runs into something.
        _, clearest, clearest_c = search(entry, cand, c_cand, False)
        if clearest_c.minimum >= 0.0 > best_c.minimum:
            return clearest
    if best_c.minimum >= 0.0:
        return best  # it grazes an object, and no path by way of its corner is clear
    # Every path runs into something: over the top of the fixtures it runs into, if that
    # is clear (only then: it adds a descent onto the target).
    over = _over_waypoint(target, best_c, obstacles, threshold, geo)
    if over is None:
        return best
    cand = finish(start, cur, over)
    if gap(cand, t_free, t_end, threshold).first_below is None:
        return cand
    # Tucked, risen close to the body to the height of `over` and out from there, no faster
    # than the arms' free-move acceleration: the latest such reach that is clear (the hands
    # stay in as long as they can: a reach that starts early, while the object is still
    # behind, is blended across the chest, where the arm cannot follow).
    raised = lifted_tuck_waypoint(hand, tuck_y, over, trunk, geo)
    reach = math.dist(raised.point, world_to_trunk(trunk, t_end, over.point))
    need = rest_to_rest_duration(reach, geo.hand_accel_limit)
    t_first = t_free + tuck_time + geo.tuck_lift_duration
    n = int((t_end - need - t_first) / k.REACH_START_STEP + 1e-9)
    for j in range(n, -1, -1):
        t_r = t_first + j * k.REACH_START_STEP
        cand = tucked(t_free, t_free + tuck_time, t_r, raised, over)
        if cand[-2].t1 - t_r < need:
            continue
        if gap(cand, t_free, t_end, threshold).first_below is None:
            return cand
    return best


def _over_waypoint(
    target: HandWaypoint,
    best: Clearance,
    obstacles: tuple[Obstacle, ...],
    threshold: tuple[float, ...],
    geo: PlanGeometry,
) -> HandWaypoint | None:
    """The point (world) above a "world" `target` from which an over-the-top approach comes
    down onto it, or None (a "trunk" target, or nothing to go over): as high as the highest
    top of the fixtures that the `best` path comes within their `threshold` (m, in the order
    of `obstacles`) of, plus the hand's radius, the clearance asked for and the trunk's
    position error that the check allows for (TRUNK_POSITION_ERROR, which a trunk-relative
    stretch of the path moves by), if that is above the target.

    Why: a pick during a turn reaches across the trunk frame while the trunk turns, and the
    right hand of a robot turning left to a table passes the platform beside it; where that
    platform's top is a few cm above the grasp height, every level path (straight, tucked,
    by the object's near corner) cuts its corner. HECTOR envelope seed 71021, transfer-028:
    the best path went 4 cm into a platform 1.7 cm higher than the grasp; the hand met it at
    1.2 s and pushed the trunk 10 cm off its turn, the grasp closed 10 cm off the parcel's
    centre, the parcel hung 20-30 deg and snagged the platform's corner. HECTOR seed 76021,
    transfer-031: the left hand's level path, at the platform's top (0.1 cm above it), went
    2.9 cm into its edge; in MuJoCo the hand leant on the platform for 1.2 s in the turn, the
    trunk drifted 13 cm and the robot fell in both strategies."""
    if target.frame != "world":
        return None
    tx, ty, tz = target.point
    tops = [
        ob.center[2] + ob.half[2]
        for ob, near, limit in zip(obstacles, best.by_obstacle, threshold, strict=True)
        if ob.name.startswith("fixture:") and near < limit
    ]
    if not tops:
        return None
    z = max(tops) + geo.hand_radius + k.APPROACH_CLEARANCE + k.TRUNK_POSITION_ERROR
    return HandWaypoint((tx, ty, z), "world") if z > tz else None


def _entry_finish(
    t_r: float,
    t_end: float,
    frm: HandWaypoint,
    entry: HandWaypoint,
    target: HandWaypoint,
    task_index: int,
    accel: float,
) -> list[HandSegment]:
    """`frm` at t_r to `entry`, then a slide along the object's side to `target` at t_end (s):
    the slide takes what a rest-to-rest move of its length needs at `accel` (m/s^2, the
    robot's hand_accel_limit), at most half of the time there is (both are "world" points)."""
    slide = rest_to_rest_duration(math.dist(entry.point, target.point), accel)
    t_s = t_end - min(slide, 0.5 * (t_end - t_r))
    return [
        HandSegment(t_r, t_s, frm, entry, task_index, "reach"),
        HandSegment(t_s, t_end, entry, target, task_index, "slide"),
    ]


def retreat_segments(
    hand: int,
    done: list[HandSegment],
    task_index: int,
    t0: float,
    t1: float,
    opened: HandWaypoint,
    back: HandWaypoint,
    trunk: TrunkPath,
    obstacles: tuple[Obstacle, ...],
    geo: PlanGeometry = HECTOR_GEOMETRY,
) -> list[HandSegment]:
    """Segments from the opened hand at t0 (s) to the tucked pose at t1 (s) (the default pose
    could rest beside, or inside, what was just put down). Straight when that keeps
    APPROACH_CLEARANCE, otherwise first `back` along the object's side to behind its near
    face (world), then in; the clearer of the two if neither is clear."""
    tuck = tuck_waypoint(hand, geo.hand_tuck_in_trunk[1], geo)
    direct = [HandSegment(t0, t1, opened, tuck, task_index, "retract")]
    c_direct = path_clearance(
        hand, done, direct, t0, t1, trunk, obstacles, k.APPROACH_CLEARANCE, geo=geo
    )
    if c_direct.first_below is None:
        return direct
    t_back = t0 + k.DROP_BACK_SHARE * (t1 - t0)
    via = [
        HandSegment(t0, t_back, opened, back, task_index, "back"),
        HandSegment(t_back, t1, back, tuck, task_index, "retract"),
    ]
    c_via = path_clearance(hand, done, via, t0, t1, trunk, obstacles, k.APPROACH_CLEARANCE, geo=geo)
    return via if c_via.minimum > c_direct.minimum else direct


@dataclass(frozen=True, slots=True)
class ThrowLine:
    """The straight line a throw pushes the object's centre along (world, m): at rest at
    `wind`, at the throw velocity `velocity` (m/s, world) from `cruise` to `release`, at rest
    again at `stop`; `lateral` is the trunk's left (world unit vector) at the release."""

    wind: Vec3
    cruise: Vec3
    release: Vec3
    stop: Vec3
    velocity: Vec3
    lateral: Vec3


def clear_throw_line(
    line: ThrowLine, radius: float, obstacles: tuple[Obstacle, ...], t_wind: float
) -> ThrowLine:
    """The throw line raised, if need be, so that an object of `radius` (m) pushed along it
    keeps THROW_CLEARANCE (m) from every fixture and object (sampled every 1 cm from the
    wind-up to the stop; obstacles at `t_wind`, s). The commanded release velocity fixes the
    line's direction, not its height: laid out from the carry pose, a line with a shallow
    upward component passed 1-3 cm over tables 0.48-0.53 m high and the ball caught the table
    (envelope seed 2026, throws)."""
    n = max(2, int(math.dist(line.wind, line.stop) / 0.01) + 1)
    # Raising by the gap that is missing is exact over a flat top; near a top's edge the gap
    # grows more slowly than the line rises, so a few passes settle it.
    for _ in range(5):
        worst = math.inf
        for i in range(n):
            f = i / (n - 1)
            p = (
                line.wind[0] + f * (line.stop[0] - line.wind[0]),
                line.wind[1] + f * (line.stop[1] - line.wind[1]),
                line.wind[2] + f * (line.stop[2] - line.wind[2]),
            )
            for ob in obstacles:
                worst = min(worst, ob.distance(p, t_wind) - radius)
        lift = k.THROW_CLEARANCE - worst
        if not math.isfinite(lift) or lift <= 1e-6:
            return line
        line = ThrowLine(
            (line.wind[0], line.wind[1], line.wind[2] + lift),
            (line.cruise[0], line.cruise[1], line.cruise[2] + lift),
            (line.release[0], line.release[1], line.release[2] + lift),
            (line.stop[0], line.stop[1], line.stop[2] + lift),
            line.velocity,
            line.lateral,
        )
    return line


def throw_line(
    trunk: TrunkPath,
    velocity_body: tuple[float, float, float],
    t_wind: float,
    t_cruise: float,
    t_release: float,
    t_follow: float,
    geo: PlanGeometry = HECTOR_GEOMETRY,
) -> ThrowLine:
    """The throw line for the commanded body-frame velocity (m/s) and phase times (s).

    It is laid out in the world from the planned trunk pose at the release, so that the
    hands' world velocity there is the commanded one whatever the trunk does (it recoils as
    the load is pushed): it ends THROW_STOP_OFFSET beyond the carry pose along the throw
    direction (`geo`'s CARRY_FORWARD and THROW_STOP_OFFSET). From rest at the wind-up point
    the quintic reaches the speed v after v T / 2 (accelerate), holds it for v T (cruise: the
    hands' tracking catches up) and comes back to rest after v T / 2 (follow-through)."""
    vx, vy, vz = velocity_body
    speed = math.sqrt(vx * vx + vy * vy + vz * vz)
    u_body = (vx / speed, vy / speed, vz / speed) if speed > 1e-9 else (1.0, 0.0, 0.0)
    bx, by, byaw, *_ = trunk.pose_at(t_release)
    c, s = math.cos(byaw), math.sin(byaw)
    u = (c * u_body[0] - s * u_body[1], s * u_body[0] + c * u_body[1], u_body[2])
    q = along((geo.carry_forward, 0.0, k.CARRY_HEIGHT), geo.throw_stop_offset, u_body)
    stop = (bx + c * q[0] - s * q[1], by + s * q[0] + c * q[1], trunk.height + q[2])
    v = speed * k.THROW_SPEED_GAIN
    release = along(stop, -v * (t_follow - t_release) / 2.0, u)
    cruise = along(release, -v * (t_release - t_cruise), u)
    wind = along(cruise, -v * (t_cruise - t_wind) / 2.0, u)
    return ThrowLine(wind, cruise, release, stop, (u[0] * v, u[1] * v, u[2] * v), (-s, c, 0.0))
