"""Manipulation plan: hand target tracks, hand contacts (sigma_H), object holds (sigma_e).

Phase fractions and poses are the named constants of `locoplan.plan.constants`; the hand paths
themselves (approach, retreat, throw line) are `locoplan.plan.hand_paths`. Geometry:

- pick: the approach direction is horizontal, from the robot's planned position at the contact
  instant to the object's centre; the grasp axis is across it (the left hand on the left of the
  approach). Pre-grasp points lie GRASP_CLEARANCE (the robot's) outside the object's sides, reached
  without sweeping through the scene (tucking the hands in first if the trunk turns or walks towards
  the object); the hands close until their spheres touch the sides, then press GRASP_SQUEEZE in. A
  box carried through a walk, turn or steps is gripped above its centre (it hangs level from the two
  point grips) and picked with PICK_CARRIED's phases, otherwise at its centre with PICK_STANDING's.
  After the grip an object held standing is raised straight up, then brought up to CARRY_HEIGHT in
  trunk as far ahead as it was picked, and settles in to CARRY_FORWARD while the hands are free; one
  carried through locomotion is pulled in to `carry_in` (its near face CARRY_IN_GAP from the trunk's
  front), no faster than `pull_accel` allows for its mass: as far as that goes during the raise, the
  rest in the carry move, up to the carry height and in at once, which takes the time it needs past
  the pick's end (`_carry_move`; a "pull" after it if the object's drop comes first), and stays
  there. A box whose grasp leaves the arms no room for its lift's lean (the compiler's
  `payload.behind_grips`) is gripped GRIP_BEHIND_CENTRE nearer the robot than its centre and
  raised straight up for RAISE_UP_SHARE of the raise before it is pulled in.
- drop: the object's centre goes to `at`, or onto the fixture's top at the fully supported
  point nearest the robot's planned position at the release instant; the grasp axis is across
  the robot-to-target direction. The object hovers above the place point (moving with the
  trunk), is lowered onto it (world), released; the hands open (wider on the side a conveyor
  carries the object to) and retreat to the tucked pose clear of it.
- throw: the hands push the object along a straight world line from a wind-up point,
  reaching the commanded velocity (relative to the planned trunk motion, trunk axes) before
  the release and holding it there, stop squeezing, let go and open while they stop.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

from locoplan.plan import constants as k
from locoplan.plan.clearance import Obstacle, fixture_obstacle, object_obstacle
from locoplan.plan.errors import InfeasiblePlanError, PlanError
from locoplan.plan.events import PlanEvent
from locoplan.plan.geometry import (
    approach_direction,
    ballistic_landing,
    half_extents,
    place_on_fixture,
    support_half_width,
)
from locoplan.plan.hand_paths import (
    HAND_NAMES,
    SIDE,
    PreGrasp,
    along,
    approach_segments,
    beside,
    carry_forward,
    carry_in,
    clear_throw_line,
    default_waypoint,
    grip_behind,
    grip_height,
    heavy_pull,
    initial_waypoint,
    pregrasp_offset,
    pull_accel,
    rest_to_rest_distance,
    rest_to_rest_duration,
    retreat_segments,
    settle_in,
    throw_line,
    tuck_waypoint,
    world_to_trunk,
)
from locoplan.plan.hands import HandSegment, HandTrack, HandWaypoint, Vec3, make_track
from locoplan.plan.intervals import Intervals, merge_intervals
from locoplan.plan.robot_geometry import HECTOR_GEOMETRY, PlanGeometry
from locoplan.plan.tasks import PlannedTask
from locoplan.plan.trunk import TrunkPath
from locoplan.scenario.model import ObjectSpec, Scenario

_HANDS_OF = {"both": (0, 1), "left": (0,), "right": (1,)}


def carry_clearance(mass: float) -> float:
    """How far (m) a held object of `mass` (kg) is carried above the fixtures it sweeps over:
    CARRY_CLEARANCE, plus CARRY_SAG_PER_KG for every kg beyond CARRY_SAG_FROM (constants)."""
    return k.CARRY_CLEARANCE + k.CARRY_SAG_PER_KG * max(0.0, mass - k.CARRY_SAG_FROM)


@dataclass(frozen=True, slots=True)
class ObjectHold:
    """One pick .. release of an object.

    `grasp` (s): hand contact starts (sigma_H); `lift` (s): the object leaves its support and
    its weight acts on the robot (sigma_e); `release` (s): the hands let go (inf: held to the
    end). `hands`: "L"/"R" names. `half_width` (m): half the object's width across the grip;
    `yaw_in_grasp` (rad): object yaw minus approach yaw at the pick; `grip_height` (m): how far
    above the object's centre the hands hold it; `carry_top` (m): the highest fixture top the
    object sweeps over while carried (`_Builder.carry_top`, 0 if none). `pre_lean` (m): how far the
    trunk may stand back from the object at the lift-off with the arms still reaching its grip
    points (`locoplan.plan.payload.pre_lean_room`): where a foot steps within a second of
    the lift-off, the controller leans back before the load comes on by the equal-margin
    share of the shift, at most this far; 0 until the compiler sets it. `grip_behind` (m): how
    far nearer the robot than the object's centre the hands hold it, across the line between
    them (`hand_paths.grip_behind`; 0 for a centre grip). `slow_lift`: a heavy object held
    standing whose pick lasts at least `compiler.HEAVY_PICK_MIN` (`compiler._with_slow_lifts`):
    its weight is to come onto the hands no faster than the load ramp, so that the robot's
    lean back follows it (the controller's `_lift_mass`); False until the compiler sets it.
    """

    object: str
    mass: float
    hands: tuple[str, ...]
    pick_task: int
    grasp: float
    lift: float
    release: float
    release_task: int | None
    release_kind: Literal["drop", "throw"] | None
    half_width: float
    yaw_in_grasp: float
    grip_height: float = 0.0
    carry_top: float = 0.0
    pre_lean: float = 0.0
    grip_behind: float = 0.0
    slow_lift: bool = False


@dataclass(frozen=True, slots=True)
class ObjectTarget:
    """Where an object should end up.

    kind "place": `position` is the object's centre on its support (world, m) at `time` (the
    release instant), on `fixture` (None for `at`); a conveyor carries it on from there.
    "throw": `position` is the ballistic landing point on the floor from the planned release
    (fixtures ignored). "carried": still held at the end, `position` None. "untouched": never
    picked, `position` is where it starts.
    """

    object: str
    kind: Literal["place", "throw", "carried", "untouched"]
    position: Vec3 | None
    yaw: float | None
    fixture: str | None
    time: float | None


@dataclass(frozen=True, slots=True)
class HandContact:
    """Hand `hand` touches `object` on [t0, t1) (s); t1 = inf when never released."""

    hand: str
    object: str
    t0: float
    t1: float


@dataclass(frozen=True, slots=True, eq=False)
class ManipulationPlan:
    """Everything manipulation: per-hand tracks, contacts and active intervals, object holds
    (in pick order), object targets and the grasp/lift/release events."""

    tracks: tuple[HandTrack, HandTrack]
    contacts: tuple[tuple[HandContact, ...], tuple[HandContact, ...]]
    contact_intervals: tuple[Intervals, Intervals]
    active_intervals: tuple[Intervals, Intervals]
    holds: tuple[ObjectHold, ...]
    held_intervals: Intervals
    targets: dict[str, ObjectTarget]
    events: tuple[PlanEvent, ...]


@dataclass
class _OpenHold:
    obj: str
    mass: float
    hands: tuple[int, ...]
    pick: PlannedTask
    grasp: float
    lift: float
    half_width: float
    yaw_in_grasp: float
    grip_height: float
    carry_top: float
    grip_behind: float


@dataclass(frozen=True, slots=True)
class _DropGeometry:
    """`_Builder._drop_geometry`: the object's place point `target` (world, m) and yaw (rad),
    a belt's `drift` (m/s), the placed object as an obstacle, and per hand its (put, hover,
    opened, back) points (world, m)."""

    target: Vec3
    obj_yaw: float
    drift: tuple[float, float]
    placed: Obstacle
    points: dict[int, tuple[Vec3, Vec3, Vec3, Vec3]]


def carry_reach(obj: ObjectSpec, forward: float) -> float:
    """How far (m) from the trunk axis a held object reaches: its centre `forward` ahead
    plus its footprint's half diagonal."""
    hx, hy, _ = half_extents(obj)
    return forward + math.hypot(hx, hy)


@dataclass
class _Builder:
    scenario: Scenario
    trunk: TrunkPath
    tasks: tuple[PlannedTask, ...] = ()
    segments: tuple[list[HandSegment], list[HandSegment]] = field(default_factory=lambda: ([], []))
    contacts: tuple[list[HandContact], list[HandContact]] = field(default_factory=lambda: ([], []))
    active: tuple[list[tuple[float, float]], list[tuple[float, float]]] = field(
        default_factory=lambda: ([], [])
    )
    holds: list[ObjectHold] = field(default_factory=list)
    open_holds: dict[str, _OpenHold] = field(default_factory=dict)
    hand_holds: list[str | None] = field(default_factory=lambda: [None, None])
    state: dict[str, tuple[float, float, float, float]] = field(default_factory=dict)
    # Objects placed on a moving belt: drift velocity (m/s, world xy) and since when (s).
    drift: dict[str, tuple[tuple[float, float], float]] = field(default_factory=dict)
    targets: dict[str, ObjectTarget] = field(default_factory=dict)
    events: list[PlanEvent] = field(default_factory=list)
    # When the run ends (s): how long a belt carries what is put on it.
    t_end: float = math.inf
    # Lift-off and touchdown times (s) of every planned foot swing, both feet.
    swings: tuple[tuple[float, float], ...] = ()
    # The weakest leg joint's torque limit (N m).
    leg_torque: float = math.inf
    # When each hand's last retreat ends (s): it may outlast its drop.
    retreat_end: list[float] = field(default_factory=lambda: [-math.inf, -math.inf])
    # The robot's figures (hand poses, hand radius, carry distance, trunk front).
    geom: PlanGeometry = HECTOR_GEOMETRY
    # Objects gripped at their centre although carried through locomotion (the compiler's
    # `payload.centre_grips`: their carry pose is out of the arms' reach).
    centre_grips: frozenset[str] = frozenset()
    # Objects gripped nearer the robot than their centre and raised straight up before they
    # are pulled in (the compiler's `payload.behind_grips`: at their grasp the arms lack the
    # room for the lean their lift needs).
    behind_grips: frozenset[str] = frozenset()
    # The earliest end (s) of each drop's hover, by the drop's task index (the compiler's
    # `payload.reachable_hovers`: where the hover as timed is out of the arms' reach); past
    # the latest end its window allows, the time whose trunk pose places the hover.
    hover_ends: Mapping[int, float] = field(default_factory=dict)
    initial: tuple[HandWaypoint, HandWaypoint] = field(
        default_factory=lambda: (default_waypoint(0), default_waypoint(1))
    )

    def __post_init__(self) -> None:
        for name, obj in self.scenario.objects.items():
            p = obj.position
            self.state[name] = (p[0], p[1], p[2], math.radians(obj.yaw))
        # Each hand rests where it starts until its first manipulation task (or the end).
        last = max((t.end for t in self.tasks), default=0.0)
        obstacles = self.obstacles()
        left, right = (
            initial_waypoint(
                h, self.trunk, obstacles, min(self.next_hand_use(h, 0.0), last), self.geom
            )
            for h in (0, 1)
        )
        self.initial = (left, right)

    def steps_during(self, t0: float, t1: float) -> bool:
        """Whether a foot swings (the robot stands on one foot) anywhere in [t0, t1] (s)."""
        return any(a < t1 and b > t0 for a, b in self.swings)

    def current(self, h: int) -> HandWaypoint:
        return self.segments[h][-1].end if self.segments[h] else self.initial[h]

    def add(self, h: int, seg: HandSegment) -> None:
        self.segments[h].append(seg)

    def check_free(self, task: PlannedTask, hands: tuple[int, ...]) -> None:
        for h in hands:
            if self.segments[h] and self.segments[h][-1].t1 > task.start + 1e-9:
                prev = self.segments[h][-1]
                raise PlanError(
                    f"{task.action} starts at {task.start:g} s while the {HAND_NAMES[h]} hand is "
                    f"still busy with task {prev.task_index} (until {prev.t1:g} s)",
                    task.index,
                )

    def _no_room_message(self, h: int, name: str, room: PreGrasp) -> str:
        """Why the hand `h` cannot wait beside `name` before the grasp, and what would do:
        `room` is the best place there was (`pregrasp_offset`). Between the side and the
        obstacle (the offset above its least) the sphere gains half of what the obstacle
        moves away; at its least offset all of it."""
        what = room.obstacle.split(":", 1)[-1]
        short = k.PREGRASP_GAP - room.clearance
        between = room.offset > self.geom.hand_radius + k.PREGRASP_GAP + 1e-9
        return (
            f"infeasible (hand room): no room for the {HAND_NAMES[h]} hand beside '{name}' "
            "before the grasp: "
            f"wherever it waits between the side of '{name}' and '{what}', its sphere "
            f"({2.0 * self.geom.hand_radius:.3f} m across) keeps at most "
            f"{room.clearance:+.3f} m from '{what}' ({k.PREGRASP_GAP:.3f} m needed); move "
            f"'{what}' {(2.0 if between else 1.0) * short:.3f} m further from '{name}'"
        )

    def release_of(self, pick: PlannedTask) -> PlannedTask | None:
        """The first drop or throw of what `pick` picks up, starting after the pick starts
        (manipulation tasks never overlap, so after it ends), or None."""
        for t in self.tasks:
            if t.action in ("drop", "throw") and t.object == pick.object and t.start >= pick.start:
                return t
        return None

    def carried_while_moving(self, pick: PlannedTask) -> bool:
        """Whether the robot walks, turns or steps while it holds what `pick` picks up (from
        the pick's start to the first drop or throw of that object, or the end)."""
        release = self.release_of(pick)
        until = math.inf if release is None else release.end
        return any(
            t.action in ("walk", "turn", "step") and t.start < until and t.end > pick.start
            for t in self.tasks
        )

    def next_use(self, pick: PlannedTask) -> float:
        """Start (s) of the first task after `pick` that drops or throws its object or uses
        one of its hands (inf if none)."""
        hands = set(_HANDS_OF[pick.hands or "both"])
        for t in self.tasks:
            if t.start < pick.end - 1e-9 or t.index == pick.index:
                continue
            if t.action in ("drop", "throw") and t.object == pick.object:
                return t.start
            if t.action == "pick" and hands & set(_HANDS_OF[t.hands or "both"]):
                return t.start
        return math.inf

    def next_hand_use(self, hand: int, after: float) -> float:
        """Start (s) of the first manipulation task starting at or after `after` that may use
        `hand` (inf if none)."""
        starts = [
            t.start
            for t in self.tasks
            if t.action in ("pick", "drop", "throw")
            and t.start >= after - 1e-9
            and hand in _HANDS_OF[t.hands or "both"]
        ]
        return min(starts, default=math.inf)

    def carry_top(self, pick: PlannedTask, obj: ObjectSpec, forward: float) -> float:
        """Highest top (m) of the fixtures that the object picked by `pick` can sweep over
        while it is carried (0 if none): `swept_top` from the pick's start until its release
        starts (or the last locomotion task ends).

        Why: a box carried at the pick's height swung into the side of a higher target while
        the robot turned towards it (envelope seed 5, transfer-012: box bottom 0.514 m, the
        platform's top 0.526 m); the blocked turn pushed the trunk 35 cm off its
        turn-in-place point, and the robot fell at the drop."""
        release = self.release_of(pick)
        if release is not None:
            until = release.start
        else:
            until = max([t.end for t in self.tasks if t.kind == "locomotion"] + [pick.end])
        return self.swept_top(pick.start, until, carry_reach(obj, forward))

    def swept_top(self, t0: float, t1: float, reach: float, skip: str | None = None) -> float:
        """Highest top (m) of the fixtures (but `skip`) whose footprint comes within `reach`
        (m) of the trunk's vertical axis anywhere on its planned path over [t0, t1]; 0 if
        none. The path is sampled every SWEEP_SAMPLE s."""
        n = max(1, math.ceil((t1 - t0) / k.SWEEP_SAMPLE))
        poses = [self.trunk.pose_at(t0 + (t1 - t0) * i / n) for i in range(n + 1)]
        top = 0.0
        for name, fixture in self.scenario.fixtures.items():
            if name == skip:
                continue
            box = fixture_obstacle(name, fixture)
            height = box.center[2] + box.half[2]
            if height <= top:
                continue
            if any(box.distance((x, y, box.center[2]), 0.0) < reach for x, y, *_ in poses):
                top = height
        return top

    def obstacles(self) -> tuple[Obstacle, ...]:
        """Fixtures and every object not held now, where the plan has put them so far."""
        out = [fixture_obstacle(n, f) for n, f in self.scenario.fixtures.items()]
        for name, obj in self.scenario.objects.items():
            if name in self.open_holds:
                continue
            x, y, z, yaw = self.state[name]
            drift, t_ref = self.drift.get(name, ((0.0, 0.0), 0.0))
            out.append(object_obstacle(name, obj, (x, y, z), yaw, drift, t_ref))
        return tuple(out)

    # --- pick ------------------------------------------------------------------------------
    def pick(self, task: PlannedTask) -> None:
        name = task.object or ""
        if name not in self.scenario.objects:
            known = ", ".join(sorted(self.scenario.objects)) or "none"
            raise PlanError(f"unknown object '{name}' (declared: {known})", task.index)
        if name in self.open_holds:
            raise PlanError(f"'{name}' is already held", task.index)
        hands = _HANDS_OF[task.hands or "both"]
        for h in hands:
            if self.hand_holds[h] is not None:
                raise PlanError(
                    f"the {HAND_NAMES[h]} hand already holds '{self.hand_holds[h]}'", task.index
                )
        self.check_free(task, hands)
        obj = self.scenario.objects[name]
        ox, oy, oz, oyaw = self.state[name]
        moving = self.carried_while_moving(task)
        phases = k.PICK_CARRIED if moving else k.PICK_STANDING
        t_reach = task.at_fraction(phases.reach_end)
        t_contact = task.at_fraction(phases.contact)
        t_lift = task.at_fraction(phases.liftoff)
        t_raise = task.at_fraction(phases.raise_end)
        rx, ry, ryaw, *_ = self.trunk.pose_at(t_contact)
        ax, ay = approach_direction(rx, ry, ox, oy, ryaw)
        lx, ly = -ay, ax
        half = support_half_width(obj, oyaw, lx, ly)
        depth = support_half_width(obj, oyaw, ax, ay)
        obstacles = self.obstacles()
        geom = self.geom
        gripped_above = moving and name not in self.centre_grips
        lift = grip_height(obj, geom) if gripped_above else 0.0
        gz = oz + lift
        # The grip points' midpoint (world): `back` nearer the robot than the centre for a box
        # carried to a drop (GRIP_BEHIND_CENTRE); every hand quantity below is the hands'
        # (the object's centre is `back` further ahead).
        release = self.release_of(task)
        to_drop = release is not None and release.action == "drop"
        behind = gripped_above and to_drop and name in self.behind_grips
        back = grip_behind(obj, depth, geom) if behind else 0.0
        hx, hy = ox - back * ax, oy - back * ay
        forward = carry_forward(self.trunk.pose_at(task.end), hx, hy, geom)
        # Carried through locomotion: in to `carry_in` (hand_paths). The raise pulls it in
        # by `pull` (m, along the approach) as it goes up, no faster than `pull_accel` for its
        # mass, and the rest of the way (to `x_in`, m ahead of the trunk) in the carry move
        # (`_carry_move`: up and in at once, past the pick's end if it needs the time);
        # a heavy object (PULL_FAST_SHARE) comes the whole way in before the first step if
        # the robot stands on both feet during the raise (`_heavy_pull_accel`).
        pull = 0.0
        t_pull = t_lift
        x_in = forward
        # The next task that uses the hands (inf if none): the carry move, the heavy pull and
        # the settling-in end by then.
        t_settle = self.next_use(task)
        accel = pull_accel(obj.mass, geom)
        raise_accel = accel
        if moving:
            target = carry_in(depth - back, geom)
            # Gripped behind its centre: straight up first (RAISE_UP_SHARE), pulled in over
            # the rest of the raise.
            if back > 0.0:
                t_pull = t_raise - k.RAISE_UP_SHARE * (t_raise - t_lift)
            if target < forward:
                ahead = world_to_trunk(self.trunk, t_raise, (hx, hy, oz))[0]
                pull = max(0.0, ahead - target)
                heavy = heavy_pull(obj.mass, ahead + back, self.leg_torque)
                if heavy and not self.steps_during(t_lift, t_raise):
                    rise = self._carry_height(
                        obj,
                        self.carry_top(task, obj, target + back),
                        gz + phases.raise_height,
                        lift,
                    )
                    rise -= gz + phases.raise_height - self.trunk.height
                    raise_accel, accel = self._heavy_pull_accel(
                        task, t_pull, t_raise, t_settle, pull, rise, accel
                    )
                pull = min(pull, rest_to_rest_distance(t_raise - t_pull, raise_accel))
                forward, x_in = max(target, ahead - pull), target
        # Then, for an object held standing, while the hands have nothing else to do (until
        # t_settle), it comes in to CARRY_FORWARD slowly enough not to set it swinging.
        swept = self.carry_top(task, obj, forward + back)
        carry_z = self._carry_height(obj, swept, gz + phases.raise_height, lift)
        others = tuple(ob for ob in obstacles if ob.name != f"object:{name}")
        for h in hands:
            side = SIDE[h]
            lateral = (side * lx, side * ly)
            room = pregrasp_offset((hx, hy, gz), lateral, half, others, t_reach, geom)
            if room.clearance < k.PREGRASP_GAP:
                raise InfeasiblePlanError(
                    self._no_room_message(h, name, room), task.index, loc=("tasks", task.index)
                )
            pre = beside((hx, hy, gz), side * (half + room.offset), lx, ly)
            # Beside the object's near corner, grasp_clearance outside its near face (as `pre`
            # is outside its side unless a fixture beside the object brings the hand in:
            # `pregrasp_offset`): where a reach that would cut the corner goes first.
            entry = beside(pre, -(depth + self.geom.grasp_clearance), ax, ay)
            touch = beside((hx, hy, gz), side * (half + geom.hand_radius), lx, ly)
            grip = beside((hx, hy, gz), side * (half - k.GRASP_SQUEEZE), lx, ly)
            raised = (grip[0] - pull * ax, grip[1] - pull * ay, gz + phases.raise_height)
            carry = (forward, side * (half - k.GRASP_SQUEEZE), carry_z)
            w_pre = HandWaypoint(pre, "world")
            w_touch = HandWaypoint(touch, "world")
            w_grip = HandWaypoint(grip, "world")
            w_raised = HandWaypoint(raised, "world")
            w_carry = HandWaypoint(carry, "trunk")
            i = task.index
            tuck_y = max(geom.hand_tuck_in_trunk[1], half + room.offset)
            approach = approach_segments(
                h,
                self.segments[h],
                task.start,
                i,
                w_pre,
                t_reach,
                tuck_y,
                self.trunk,
                obstacles,
                self.initial[h],
                geom,
                HandWaypoint(entry, "world"),
            )
            for seg in approach:
                self.add(h, seg)
            self.add(h, HandSegment(t_reach, t_contact, w_pre, w_touch, i, "squeeze"))
            self.add(h, HandSegment(t_contact, t_lift, w_touch, w_grip, i, "grip"))
            if t_pull > t_lift and pull > 0.0:
                up = (grip[0], grip[1], gz + k.RAISE_UP_SHARE * phases.raise_height)
                w_up = HandWaypoint(up, "world")
                self.add(h, HandSegment(t_lift, t_pull, w_grip, w_up, i, "raise"))
                self.add(h, HandSegment(t_pull, t_raise, w_up, w_raised, i, "raise"))
            else:
                self.add(h, HandSegment(t_lift, t_raise, w_grip, w_raised, i, "raise"))
            t_carry, x_to = self._carry_move(task, t_raise, raised, carry, x_in, accel, t_settle)
            carry = (x_to, carry[1], carry[2])
            w_carry = HandWaypoint(carry, "trunk")
            self.add(h, HandSegment(t_raise, t_carry, w_raised, w_carry, i, "carry"))
            t_end = t_carry
            forward = x_to
            settles = not moving and abs(forward - geom.carry_forward) > 1e-3
            if settles and t_settle - t_carry >= k.CARRY_SETTLE_MIN:
                dist, took = settle_in(abs(forward - geom.carry_forward), t_settle - t_carry)
                x_to = forward + math.copysign(dist, geom.carry_forward - forward)
                w_settled = HandWaypoint((x_to, carry[1], carry[2]), "trunk")
                self.add(h, HandSegment(t_carry, t_carry + took, w_carry, w_settled, i, "settle"))
                t_end = t_carry + took
            elif moving and forward - x_in > 1e-3 and t_settle > t_carry:
                dist, took = settle_in(forward - x_in, t_settle - t_carry, accel, 0.0)
                w_in = HandWaypoint((forward - dist, carry[1], carry[2]), "trunk")
                self.add(h, HandSegment(t_carry, t_carry + took, w_carry, w_in, i, "pull"))
                t_end = t_carry + took
            self.hand_holds[h] = name
            self.active[h].append((min(task.start, approach[0].t0), t_end))
        self.open_holds[name] = _OpenHold(
            name,
            obj.mass,
            hands,
            task,
            t_contact,
            t_lift,
            half,
            oyaw - math.atan2(ay, ax),
            lift,
            swept,
            back,
        )
        self.events.append(PlanEvent(t_contact, "grasp", task.index, name))
        self.events.append(PlanEvent(t_lift, "lift", task.index, name))

    def _carry_height(
        self, obj: ObjectSpec, swept_top: float, raised_z: float, lift: float
    ) -> float:
        """Height (m, in trunk) of the grip points in the carry pose of the object `obj`,
        raised to `raised_z` (world, m), gripped `lift` above its centre: at least
        CARRY_HEIGHT, no lower than it was raised (a box picked from a table higher than the
        carry pose would otherwise be lowered back towards that table's top while the robot
        turns or walks away from it: its corner caught the table's edge), and
        `carry_clearance` above `swept_top`, the highest fixture top it sweeps over
        (`carry_top`, for where it is carried)."""
        return max(
            k.CARRY_HEIGHT + lift,
            raised_z - self.trunk.height,
            swept_top + carry_clearance(obj.mass) + half_extents(obj)[2] + lift - self.trunk.height,
        )

    def _heavy_pull_accel(
        self,
        task: PlannedTask,
        t_lift: float,
        t_raise: float,
        t_next: float,
        pull: float,
        rise: float,
        gentlest: float,
    ) -> tuple[float, float]:
        """Peak accelerations (m/s^2) of the raise and of the carry move of a heavy object
        (PULL_FAST_SHARE) that the robot lifts standing on both feet: the gentlest, down to
        `gentlest` (its `pull_accel`), with which the raise (pulling in as it goes up from
        `t_lift`, s: the pick passes the end of its straight-up share) and
        the carry move (the rest of the `pull`, m, and `rise`, m up to the carry height) are
        done before the first step after the lift-off (and before the hands' next task, at
        `t_next` s, inf if none); if
        none is, the whole pull during the raise, as fast as that takes, and the carry move
        (up only) at `gentlest`.

        Why: a heavy object still far ahead in the first single support saturates the stance
        hip pitch (constants' PULL_FAST_SHARE), so it must be in before the robot steps; but
        pulled in during the raise alone, 0.2-0.35 s, a 5 kg box came 13 cm in at 7 m/s^2
        (40 N on the hands, about twice what the line feet answer at that height): the trunk
        lurched 10 cm towards it, the CoM passed the toes, the MPC's forces fell to their
        minimum and the trunk sank 12 cm with the box put back on its table (envelope seed
        24681, transfer-009, which then had 0.56 s standing before its next turn)."""
        t_raise_len = t_raise - t_lift
        fast = pull / rest_to_rest_distance(t_raise_len, 1.0) if t_raise_len > 0.0 else gentlest
        if fast <= gentlest:
            return gentlest, gentlest
        t_step = min((a for a, b in self.swings if b > t_lift), default=math.inf)
        t_by = min(t_step, max(task.end, t_next))

        def done(a: float) -> float:
            rest = pull - min(pull, rest_to_rest_distance(t_raise_len, a))
            return t_raise + rest_to_rest_duration(math.hypot(rest, max(rise, 0.0)), a)

        if done(gentlest) <= t_by:
            return gentlest, gentlest
        if done(fast) > t_by:
            return fast, gentlest
        lo, hi = gentlest, fast
        for _ in range(40):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if done(mid) <= t_by else (mid, hi)
        return hi, hi

    def _carry_move(
        self,
        task: PlannedTask,
        t_raise: float,
        raised: Vec3,
        carry: Vec3,
        x_in: float,
        accel: float,
        t_free: float,
    ) -> tuple[float, float]:
        """(end s, how far ahead m) of the "carry" move of a pick: from the `raised` world
        point at `t_raise` up to the `carry` point in trunk and, for an object carried through
        locomotion, in towards `x_in` (m ahead of the trunk) at the same time. The move peaks
        at `accel` (m/s^2, `pull_accel` for the load: the arms' and the object's reaction on
        the trunk held to HAND_ACCEL_LIMIT's force, as for a drop's lowering). It ends at the
        pick's end or when it needs, past the pick's end while the hands have nothing else to
        do, up to `t_free` (the next task that uses them); it goes in as far as that time
        allows (a "pull" segment does the rest), and at the least up to the carry height.

        Why: at the phase fractions alone, the carry gets the last 15 % of the pick's window.
        A box carried to a higher platform is raised to clear it on the way (10-12 cm), and
        in 0.15 s that accelerated 5-8 kg boxes at 15-31 m/s^2 upwards: 110-230 N more on the
        hands 0.2 m ahead of the trunk within 0.1 s. The MPC's forces fell to their minimum,
        the trunk sank 10 cm and lurched 13 cm towards the box, and the robot fell in the
        turn that followed (envelope seed 26457: walk-carry-021, -023, -025, -028 fell, the
        four picks of that seed's 200 scripts with the largest such push). Up and in at
        once, not one after the other: a 5.6 kg box raised first and pulled in only then
        stayed 0.3 s longer 0.3 m ahead while the robot stepped, and the stance hip pitch
        saturated (seed 22360, transfer-002, fell)."""
        start = world_to_trunk(self.trunk, t_raise, raised)
        t_latest = max(task.end, t_free)

        def need(x: float) -> float:
            return rest_to_rest_duration(math.dist(start, (x, carry[1], carry[2])), accel)

        x_to = min(x_in, carry[0])
        if t_raise + need(x_to) > t_latest:
            # As far in as the time allows: the 3D move within rest_to_rest_distance.
            reach = rest_to_rest_distance(t_latest - t_raise, accel)
            across = (carry[1] - start[1]) ** 2 + (carry[2] - start[2]) ** 2
            room = reach * reach - across
            x_to = carry[0] if room <= 0.0 else max(x_to, min(carry[0], start[0] - room**0.5))
        return min(max(task.end, t_raise + need(x_to)), t_latest), x_to

    def _release_hold(self, task: PlannedTask, kind: Literal["drop", "throw"]) -> _OpenHold:
        name = task.object or ""
        hold = self.open_holds.get(name)
        if hold is None:
            raise PlanError(
                f"{task.action} of '{name}', which is not held at that time", task.index
            )
        if hold.pick.end > task.start + 1e-9:
            raise PlanError(
                f"{task.action} of '{name}' starts at {task.start:g} s, before its pick "
                f"(task {hold.pick.index}) ends at {hold.pick.end:g} s",
                task.index,
            )
        self.check_free(task, hold.hands)
        return hold

    def _close_hold(
        self, hold: _OpenHold, task: PlannedTask, t_release: float, kind: Literal["drop", "throw"]
    ) -> None:
        hand_names = tuple(HAND_NAMES[h] for h in hold.hands)
        self.holds.append(
            ObjectHold(
                hold.obj,
                hold.mass,
                hand_names,
                hold.pick.index,
                hold.grasp,
                hold.lift,
                t_release,
                task.index,
                kind,
                hold.half_width,
                hold.yaw_in_grasp,
                hold.grip_height,
                hold.carry_top,
                grip_behind=hold.grip_behind,
            )
        )
        for h in hold.hands:
            self.contacts[h].append(HandContact(HAND_NAMES[h], hold.obj, hold.grasp, t_release))
            self.active[h].append((task.start, max(task.end, self.retreat_end[h])))
            self.hand_holds[h] = None
        del self.open_holds[hold.obj]
        self.events.append(PlanEvent(t_release, "release", task.index, hold.obj))

    # --- drop ------------------------------------------------------------------------------
    def drop(self, task: PlannedTask) -> None:
        hold = self._release_hold(task, "drop")
        name = hold.obj
        t_hover = task.at_fraction(k.DROP_HOVER_END)
        t_release = task.at_fraction(k.DROP_RELEASE)
        earliest = self.hover_ends.get(task.index, -math.inf)
        if earliest > t_hover:
            # The lowering keeps its share of the window, within the window.
            lowering = t_release - t_hover
            t_hover = min(earliest, task.end - lowering)
            t_release = max(t_release, t_hover + lowering)
        geo = self._drop_geometry(task, hold, t_hover, t_release)
        timed = self._drop_times(task, hold, geo, t_hover, t_release, earliest)
        if timed != (t_hover, t_release):
            t_hover, t_release = timed
            geo = self._drop_geometry(task, hold, t_hover, t_release)
        t_open = task.at_fraction(k.DROP_OPEN_END)
        obstacles = (*self.obstacles(), geo.placed)
        i = task.index
        for h in hold.hands:
            put, hover, opened, back = geo.points[h]
            w_put = HandWaypoint(put, "world")
            # The hover point moves with the trunk (where the plan has it at the hover's end):
            # while the robot still turns or walks, a world point would pull the hands (and
            # the load) hard against the trunk's lag; the lowering ends on the world point.
            # Where the hover cannot wait until the arms reach it (`hover_ends` after the
            # window's last hover end), it holds the object where the trunk will have it then.
            w_hover = HandWaypoint(
                world_to_trunk(self.trunk, max(t_hover, earliest), hover), "trunk"
            )
            w_open = HandWaypoint(opened, "world")
            w_back = HandWaypoint(back, "world")
            self.add(h, HandSegment(task.start, t_hover, self.current(h), w_hover, i, "hover"))
            self.add(h, HandSegment(t_hover, t_release, w_hover, w_put, i, "lower"))
            # Opening and retreat no faster than the feet can answer the arms' reaction
            # (rest_to_rest_duration); the retreat may run past the drop's end while the
            # hands have nothing else to do.
            free = self.geom.hand_accel_limit
            h_open = max(t_open, t_release + rest_to_rest_duration(math.dist(put, opened), free))
            self.add(h, HandSegment(t_release, h_open, w_put, w_open, i, "open"))
            tuck = tuck_waypoint(h, self.geom.hand_tuck_in_trunk[1], self.geom).point
            opened_in_trunk = world_to_trunk(self.trunk, h_open, opened)
            # The retreat goes back along the object first when a straight one would pass
            # close to it: up to about 1.4 times the straight distance.
            span = 1.4 * math.dist(opened_in_trunk, tuck)
            h_end = max(task.end, h_open + rest_to_rest_duration(span, free))
            h_end = max(min(h_end, self.next_hand_use(h, task.end)), task.end, h_open + 0.05)
            for seg in retreat_segments(
                h,
                self.segments[h],
                i,
                h_open,
                h_end,
                w_open,
                w_back,
                self.trunk,
                obstacles,
                self.geom,
            ):
                self.add(h, seg)
            self.retreat_end[h] = h_end
        self._close_hold(hold, task, t_release, "drop")
        tx, ty, tz = geo.target
        self.state[name] = (tx, ty, tz, geo.obj_yaw)
        if geo.drift != (0.0, 0.0):
            self.drift[name] = (geo.drift, t_release)
        self.targets[name] = ObjectTarget(
            name, "place", geo.target, geo.obj_yaw, task.onto, t_release
        )

    def _drop_times(
        self,
        task: PlannedTask,
        hold: _OpenHold,
        geo: _DropGeometry,
        t_hover: float,
        t_release: float,
        earliest: float = -math.inf,
    ) -> tuple[float, float]:
        """The hover's end and the release (s) of a drop: `t_hover` and `t_release` (from
        DROP_HOVER_END and DROP_RELEASE of its window), unless the lowering between them would
        accelerate the load faster than `pull_accel` allows for its mass (the arms' and the
        object's reaction on the trunk held to HAND_ACCEL_LIMIT's force, as for a pull-in).
        Then the lowering takes the time it needs from the hover, down to the hover's own
        need at that acceleration and not before `earliest` (`hover_ends`), and then from
        after `t_release`, up to the drop's end; a window too short for both shares itself
        between them in proportion to their needs.

        Why: at fixed fractions, a lowering from a hover raised to clear the table passed on
        the way (11 cm) in 0.13 s accelerated a 5.6 kg box at 37 m/s^2, and 4 cm in 0.12 s at
        16 m/s^2; the MPC's external force (-m_o a_o) then swung by 80-180 N within 0.1 s,
        and its plan sank the robot (envelope seed 6161, transfer-050: vertical forces
        100 N under the weight before the release, fell)."""
        accel = pull_accel(hold.mass, self.geom)
        lower = max(
            rest_to_rest_duration(geo.points[h][1][2] - geo.points[h][0][2], accel)
            for h in hold.hands
        )
        if t_release - t_hover >= lower:
            return t_hover, t_release
        hover_need = 0.0
        for h in hold.hands:
            cur = self.current(h)
            start = cur.point
            if cur.frame == "world":
                start = world_to_trunk(self.trunk, task.start, start)
            end = world_to_trunk(self.trunk, t_hover, geo.points[h][1])
            hover_need = max(hover_need, rest_to_rest_duration(math.dist(start, end), accel))
        hover_end = max(task.start + hover_need, t_release - lower, min(earliest, t_hover))
        release = min(task.end, max(t_release, hover_end + lower))
        if release - hover_end < lower - 1e-9:
            hover_end = task.start + (release - task.start) * hover_need / (hover_need + lower)
        return hover_end, release

    def _drop_geometry(
        self, task: PlannedTask, hold: _OpenHold, t_hover: float, t_release: float
    ) -> _DropGeometry:
        """Where a drop puts its object (from the planned trunk pose at the release) and each
        hand's place, hover (above it, clear of the fixtures passed until t_hover), opened
        and backed-off points (world)."""
        name = hold.obj
        obj = self.scenario.objects[name]
        rx, ry, ryaw, *_ = self.trunk.pose_at(t_release)
        if task.onto is not None:
            fixture = self.scenario.fixtures.get(task.onto)
            if fixture is None:
                known = ", ".join(sorted(self.scenario.fixtures)) or "none"
                raise PlanError(f"unknown fixture '{task.onto}' (declared: {known})", task.index)
            travel = 0.0
            if fixture.kind == "conveyor" and fixture.speed and math.isfinite(self.t_end):
                travel = fixture.speed * max(0.0, self.t_end - t_release)
            target, _ = place_on_fixture(
                task.onto,
                fixture,
                obj,
                hold.yaw_in_grasp,
                rx,
                ry,
                ryaw,
                task.index,
                travel=travel,
            )
        else:
            assert task.at is not None  # DropTask validates: exactly one of onto/at
            target = task.at
        ax, ay = approach_direction(rx, ry, target[0], target[1], ryaw)
        obj_yaw = math.atan2(ay, ax) + hold.yaw_in_grasp
        lx, ly = -ay, ax
        half = hold.half_width
        tx, ty, tz = target
        drift = (0.0, 0.0)
        if task.onto is not None:
            fixture = self.scenario.fixtures[task.onto]
            if fixture.kind == "conveyor" and fixture.speed:
                fyaw = math.radians(fixture.yaw)
                drift = (fixture.speed * math.cos(fyaw), fixture.speed * math.sin(fyaw))
        placed = object_obstacle(name, obj, target, obj_yaw, drift, t_release)
        depth = support_half_width(obj, obj_yaw, ax, ay)
        # The hover phase brings the object over the target while the robot may still turn
        # towards it: it stays clear of the other fixtures it passes (the table it came from)
        # until it is over the target, and only the lowering goes below their tops.
        # (Envelope seed 5, transfer-027: a drop starting mid-turn lowered the box onto the
        # corner of its own table for 0.9 s, 77 deg from the conveyor it was going to.)
        passed = self.swept_top(
            task.start,
            t_hover,
            carry_reach(obj, self.geom.carry_forward + k.CARRY_FORWARD_RANGE),
            task.onto,
        )
        hover_floor = 0.0
        if passed > 0.0:
            hover_floor = (
                passed + carry_clearance(hold.mass) + half_extents(obj)[2] + hold.grip_height
            )
        points: dict[int, tuple[Vec3, Vec3, Vec3, Vec3]] = {}
        for h in hold.hands:
            side = SIDE[h]
            # A belt carries the released object towards one hand: that hand opens wider by
            # how far the object comes towards it before the drop ends.
            towards = max(0.0, side * (drift[0] * lx + drift[1] * ly))
            width = half + self.geom.grasp_clearance + towards * (task.end - t_release)
            # The hands `grip_behind` nearer the robot than the object's centre (the pick's).
            grip_at = (
                tx - hold.grip_behind * ax,
                ty - hold.grip_behind * ay,
                tz + hold.grip_height,
            )
            rest = beside(grip_at, side * (half - k.GRASP_SQUEEZE), lx, ly)
            put = (rest[0], rest[1], rest[2] - k.DROP_PRESS)
            hover = (put[0], put[1], max(rest[2] + k.DROP_HOVER_HEIGHT, hover_floor))
            opened = beside(grip_at, side * width, lx, ly)
            back = beside(opened, -(depth + self.geom.grasp_clearance), ax, ay)
            points[h] = (put, hover, opened, back)
        return _DropGeometry(target, obj_yaw, drift, placed, points)

    # --- throw -----------------------------------------------------------------------------
    def throw(self, task: PlannedTask) -> None:
        hold = self._release_hold(task, "throw")
        name = hold.obj
        obj = self.scenario.objects[name]
        vx, vy, vz = task.velocity or (0.0, 0.0, 0.0)
        t_wind = task.at_fraction(k.THROW_WINDUP_END)
        t_cruise = task.at_fraction(k.THROW_ACCELERATE_END)
        t_release = task.at_fraction(k.THROW_RELEASE)
        t_follow = task.at_fraction(k.THROW_FOLLOW_END)
        line = throw_line(
            self.trunk, (vx, vy, vz), t_wind, t_cruise, t_release, t_follow, self.geom
        )
        radius = obj.size[0] if obj.shape == "sphere" else max(half_extents(obj))
        line = clear_throw_line(line, radius, self.obstacles(), t_wind)
        lat, vel = line.lateral, line.velocity
        half = hold.half_width
        up = (0.0, 0.0, 1.0)
        centre_wind, centre_cruise, centre_rel, centre_stop = (
            along(q, hold.grip_height, up)
            for q in (line.wind, line.cruise, line.release, line.stop)
        )
        i = task.index
        for h in hold.hands:
            side = SIDE[h]
            grip = side * (half - k.GRASP_SQUEEZE)
            loose = side * (half + self.geom.hand_radius)
            opened = side * (half + self.geom.grasp_clearance)
            w_wind = HandWaypoint(along(centre_wind, grip, lat), "world")
            w_cruise = HandWaypoint(along(centre_cruise, grip, lat), "world", vel)
            # No squeeze at the release: the hands only touch the object, so nothing drags it
            # once the grasp lets go.
            w_rel = HandWaypoint(along(centre_rel, loose, lat), "world", vel)
            w_stop = HandWaypoint(along(centre_stop, opened, lat), "world")
            self.add(h, HandSegment(task.start, t_wind, self.current(h), w_wind, i, "windup"))
            self.add(h, HandSegment(t_wind, t_cruise, w_wind, w_cruise, i, "accelerate"))
            self.add(h, HandSegment(t_cruise, t_release, w_cruise, w_rel, i, "cruise"))
            self.add(h, HandSegment(t_release, t_follow, w_rel, w_stop, i, "follow"))
            rest = default_waypoint(h, self.geom)
            self.add(h, HandSegment(t_follow, task.end, w_stop, rest, i, "return"))
        self._close_hold(hold, task, t_release, "throw")
        # Planned release state of the object's centre: the line's release point and the
        # commanded velocity relative to the planned trunk motion, for its landing point.
        p = line.release
        bx, by, byaw, bvx, bvy, bwz = self.trunk.pose_at(t_release)
        c, s = math.cos(byaw), math.sin(byaw)
        rwx, rwy = p[0] - bx, p[1] - by
        v = (
            c * vx - s * vy + bvx - bwz * rwy,
            s * vx + c * vy + bvy + bwz * rwx,
            vz,
        )
        landing = ballistic_landing(p, v, half_extents(obj)[2])
        self.state[name] = (*landing, self.state[name][3])
        self.targets[name] = ObjectTarget(name, "throw", landing, None, None, t_release)

    def finish(self) -> ManipulationPlan:
        for name, hold in list(self.open_holds.items()):
            self.holds.append(
                ObjectHold(
                    name,
                    hold.mass,
                    tuple(HAND_NAMES[h] for h in hold.hands),
                    hold.pick.index,
                    hold.grasp,
                    hold.lift,
                    math.inf,
                    None,
                    None,
                    hold.half_width,
                    hold.yaw_in_grasp,
                    hold.grip_height,
                    hold.carry_top,
                )
            )
            for h in hold.hands:
                self.contacts[h].append(HandContact(HAND_NAMES[h], name, hold.grasp, math.inf))
            self.targets[name] = ObjectTarget(name, "carried", None, None, None, None)
        for name, obj in self.scenario.objects.items():
            if name not in self.targets:
                p = obj.position
                pos = (p[0], p[1], p[2])
                self.targets[name] = ObjectTarget(
                    name, "untouched", pos, math.radians(obj.yaw), None, None
                )
        holds = tuple(sorted(self.holds, key=lambda x: (x.grasp, x.object)))
        contacts = (
            tuple(sorted(self.contacts[0], key=lambda c: c.t0)),
            tuple(sorted(self.contacts[1], key=lambda c: c.t0)),
        )
        return ManipulationPlan(
            tracks=(
                make_track("L", self.initial[0], self.segments[0]),
                make_track("R", self.initial[1], self.segments[1]),
            ),
            contacts=contacts,
            contact_intervals=(
                merge_intervals([(c.t0, c.t1) for c in contacts[0]]),
                merge_intervals([(c.t0, c.t1) for c in contacts[1]]),
            ),
            active_intervals=(
                merge_intervals(self.active[0] + [(c.t0, c.t1) for c in contacts[0]]),
                merge_intervals(self.active[1] + [(c.t0, c.t1) for c in contacts[1]]),
            ),
            holds=holds,
            held_intervals=merge_intervals([(x.lift, x.release) for x in holds]),
            targets=dict(sorted(self.targets.items())),
            events=tuple(self.events),
        )


def build_manipulation(
    tasks: tuple[PlannedTask, ...],
    scenario: Scenario,
    trunk: TrunkPath,
    swings: tuple[tuple[float, float], ...] = (),
    leg_torque: float = math.inf,
    geom: PlanGeometry = HECTOR_GEOMETRY,
    centre_grips: frozenset[str] = frozenset(),
    hover_ends: Mapping[int, float] | None = None,
    behind_grips: frozenset[str] = frozenset(),
) -> ManipulationPlan:
    """Hand tracks, contacts, object holds and targets for the sorted planned tasks;
    `swings`: the planned foot swings (lift-off, touchdown; s), both feet; `leg_torque`: the
    weakest leg joint's torque limit (N m); `geom`: the robot's figures; `centre_grips`: the
    objects to grip at their centre even when carried through locomotion; `hover_ends`: the
    earliest end (s) of the hover of the drops they name (by task index); `behind_grips`:
    the objects to grip nearer the robot than their centre (`hand_paths.grip_behind`)."""
    shift = max((t.shift for t in tasks), default=0.0)
    b = _Builder(
        scenario,
        trunk,
        tasks,
        t_end=scenario.end_time + shift,
        swings=swings,
        leg_torque=leg_torque,
        geom=geom,
        centre_grips=centre_grips,
        behind_grips=behind_grips,
        hover_ends=dict(hover_ends or {}),
    )
    for task in tasks:
        if task.action == "pick":
            b.pick(task)
        elif task.action == "drop":
            b.drop(task)
        elif task.action == "throw":
            b.throw(task)
    return b.finish()
