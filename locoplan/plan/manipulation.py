"""Manipulation plan: hand target tracks, hand contacts (sigma_H), object holds (sigma_e).

Phase fractions and poses are the named constants of `locoplan.plan.constants`. Geometry:

- pick: the approach direction is horizontal, from the robot's planned position at the
  contact instant to the object's centre; the grasp axis is across it (the left hand on the
  left of the approach). Pre-grasp points lie GRASP_CLEARANCE outside the object's sides at its
  centre height, contact points GRASP_SQUEEZE inside; after the grip the object is raised
  straight up, then brought to the carry pose (centre at (CARRY_FORWARD, 0, CARRY_HEIGHT) in
  trunk, hands at +-(half width - GRASP_SQUEEZE) along the trunk's y).
- drop: the object's centre goes to `at`, or onto the fixture's top at the fully supported
  point nearest the robot's planned position at the release instant; the grasp axis is across
  the robot-to-target direction.
- throw: the hands accelerate along a straight line in trunk from a wind-up point to a release
  point THROW_RELEASE_OFFSET beyond the carry pose along the throw direction, reaching the
  commanded velocity (relative to the trunk, trunk axes) at the release instant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

from locoplan.plan import constants as k
from locoplan.plan.errors import PlanError
from locoplan.plan.events import PlanEvent
from locoplan.plan.geometry import (
    approach_direction,
    ballistic_landing,
    half_extents,
    place_on_fixture,
    support_half_width,
)
from locoplan.plan.hands import HandSegment, HandTrack, HandWaypoint, Vec3, make_track
from locoplan.plan.intervals import Intervals, merge_intervals
from locoplan.plan.tasks import PlannedTask
from locoplan.plan.trunk import TrunkPath
from locoplan.scenario.model import Scenario

HAND_NAMES: tuple[str, str] = ("L", "R")
_SIDE = (1.0, -1.0)  # +y for the left hand, -y for the right
_HANDS_OF = {"both": (0, 1), "left": (0,), "right": (1,)}


@dataclass(frozen=True, slots=True)
class ObjectHold:
    """One pick .. release of an object.

    `grasp` (s): hand contact starts (sigma_H); `lift` (s): the object leaves its support and
    its weight acts on the robot (sigma_e); `release` (s): the hands let go (inf: held to the
    end). `hands`: "L"/"R" names. `half_width` (m): half the object's width across the grip;
    `yaw_in_grasp` (rad): object yaw minus approach yaw at the pick.
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


def default_waypoint(hand: int) -> HandWaypoint:
    """The default (carry-ready) hand pose in trunk."""
    x, y, z = k.HAND_DEFAULT_IN_TRUNK
    return HandWaypoint((x, _SIDE[hand] * y, z), "trunk")


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


@dataclass
class _Builder:
    scenario: Scenario
    trunk: TrunkPath
    segments: tuple[list[HandSegment], list[HandSegment]] = field(default_factory=lambda: ([], []))
    contacts: tuple[list[HandContact], list[HandContact]] = field(default_factory=lambda: ([], []))
    active: tuple[list[tuple[float, float]], list[tuple[float, float]]] = field(
        default_factory=lambda: ([], [])
    )
    holds: list[ObjectHold] = field(default_factory=list)
    open_holds: dict[str, _OpenHold] = field(default_factory=dict)
    hand_holds: list[str | None] = field(default_factory=lambda: [None, None])
    state: dict[str, tuple[float, float, float, float]] = field(default_factory=dict)
    targets: dict[str, ObjectTarget] = field(default_factory=dict)
    events: list[PlanEvent] = field(default_factory=list)

    def __post_init__(self) -> None:
        for name, obj in self.scenario.objects.items():
            p = obj.position
            self.state[name] = (p[0], p[1], p[2], math.radians(obj.yaw))

    def current(self, h: int) -> HandWaypoint:
        return self.segments[h][-1].end if self.segments[h] else default_waypoint(h)

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
        t_reach = task.at_fraction(k.PICK_REACH_END)
        t_contact = task.at_fraction(k.PICK_CONTACT)
        t_lift = task.at_fraction(k.PICK_LIFTOFF)
        t_raise = task.at_fraction(k.PICK_RAISE_END)
        rx, ry, ryaw, *_ = self.trunk.pose_at(t_contact)
        ax, ay = approach_direction(rx, ry, ox, oy, ryaw)
        lx, ly = -ay, ax
        half = support_half_width(obj, oyaw, lx, ly)
        for h in hands:
            side = _SIDE[h]
            pre = _beside((ox, oy, oz), side * (half + k.GRASP_CLEARANCE), lx, ly)
            grip = _beside((ox, oy, oz), side * (half - k.GRASP_SQUEEZE), lx, ly)
            raised = (grip[0], grip[1], oz + k.PICK_RAISE_HEIGHT)
            carry = (k.CARRY_FORWARD, side * (half - k.GRASP_SQUEEZE), k.CARRY_HEIGHT)
            w_pre = HandWaypoint(pre, "world")
            w_grip = HandWaypoint(grip, "world")
            w_raised = HandWaypoint(raised, "world")
            w_carry = HandWaypoint(carry, "trunk")
            i = task.index
            self.add(h, HandSegment(task.start, t_reach, self.current(h), w_pre, i, "reach"))
            self.add(h, HandSegment(t_reach, t_contact, w_pre, w_grip, i, "squeeze"))
            self.add(h, HandSegment(t_contact, t_lift, w_grip, w_grip, i, "grip"))
            self.add(h, HandSegment(t_lift, t_raise, w_grip, w_raised, i, "raise"))
            self.add(h, HandSegment(t_raise, task.end, w_raised, w_carry, i, "carry"))
            self.hand_holds[h] = name
            self.active[h].append((task.start, task.end))
        self.open_holds[name] = _OpenHold(
            name, obj.mass, hands, task, t_contact, t_lift, half, oyaw - math.atan2(ay, ax)
        )
        self.events.append(PlanEvent(t_contact, "grasp", task.index, name))
        self.events.append(PlanEvent(t_lift, "lift", task.index, name))

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
            )
        )
        for h in hold.hands:
            self.contacts[h].append(HandContact(HAND_NAMES[h], hold.obj, hold.grasp, t_release))
            self.active[h].append((task.start, task.end))
            self.hand_holds[h] = None
        del self.open_holds[hold.obj]
        self.events.append(PlanEvent(t_release, "release", task.index, hold.obj))

    # --- drop ------------------------------------------------------------------------------
    def drop(self, task: PlannedTask) -> None:
        hold = self._release_hold(task, "drop")
        name = hold.obj
        obj = self.scenario.objects[name]
        t_hover = task.at_fraction(k.DROP_HOVER_END)
        t_release = task.at_fraction(k.DROP_RELEASE)
        t_open = task.at_fraction(k.DROP_OPEN_END)
        rx, ry, ryaw, *_ = self.trunk.pose_at(t_release)
        if task.onto is not None:
            fixture = self.scenario.fixtures.get(task.onto)
            if fixture is None:
                known = ", ".join(sorted(self.scenario.fixtures)) or "none"
                raise PlanError(f"unknown fixture '{task.onto}' (declared: {known})", task.index)
            target, _ = place_on_fixture(
                task.onto, fixture, obj, hold.yaw_in_grasp, rx, ry, ryaw, task.index
            )
        else:
            assert task.at is not None  # DropTask validates: exactly one of onto/at
            target = task.at
        ax, ay = approach_direction(rx, ry, target[0], target[1], ryaw)
        obj_yaw = math.atan2(ay, ax) + hold.yaw_in_grasp
        lx, ly = -ay, ax
        half = hold.half_width
        tx, ty, tz = target
        for h in hold.hands:
            side = _SIDE[h]
            put = _beside(target, side * (half - k.GRASP_SQUEEZE), lx, ly)
            hover = (put[0], put[1], tz + k.DROP_HOVER_HEIGHT)
            opened = _beside(target, side * (half + k.GRASP_CLEARANCE), lx, ly)
            w_put = HandWaypoint(put, "world")
            w_hover = HandWaypoint(hover, "world")
            w_open = HandWaypoint(opened, "world")
            i = task.index
            self.add(h, HandSegment(task.start, t_hover, self.current(h), w_hover, i, "hover"))
            self.add(h, HandSegment(t_hover, t_release, w_hover, w_put, i, "lower"))
            self.add(h, HandSegment(t_release, t_open, w_put, w_open, i, "open"))
            self.add(h, HandSegment(t_open, task.end, w_open, default_waypoint(h), i, "retract"))
        self._close_hold(hold, task, t_release, "drop")
        self.state[name] = (tx, ty, tz, obj_yaw)
        self.targets[name] = ObjectTarget(name, "place", target, obj_yaw, task.onto, t_release)

    # --- throw -----------------------------------------------------------------------------
    def throw(self, task: PlannedTask) -> None:
        hold = self._release_hold(task, "throw")
        name = hold.obj
        obj = self.scenario.objects[name]
        vx, vy, vz = task.velocity or (0.0, 0.0, 0.0)
        speed = math.sqrt(vx * vx + vy * vy + vz * vz)
        ux, uy, uz = (vx / speed, vy / speed, vz / speed) if speed > 1e-9 else (1.0, 0.0, 0.0)
        t_wind = task.at_fraction(k.THROW_WINDUP_END)
        t_release = task.at_fraction(k.THROW_RELEASE)
        t_follow = task.at_fraction(k.THROW_FOLLOW_END)
        # 2 tau^3 - tau^4 from rest reaches the speed 2 L / T: the line is speed T / 2 long.
        length = speed * (t_release - t_wind) / 2.0
        length_follow = speed * (t_follow - t_release) / 2.0
        off = k.THROW_RELEASE_OFFSET
        vel = (vx, vy, vz)
        direction = (ux, uy, uz)
        for h in hold.hands:
            side = _SIDE[h]
            carry = (k.CARRY_FORWARD, side * (hold.half_width - k.GRASP_SQUEEZE), k.CARRY_HEIGHT)
            rel = _along(carry, off, direction)
            wind = _along(rel, -length, direction)
            stop = _along(rel, length_follow, direction)
            w_wind = HandWaypoint(wind, "trunk")
            w_rel = HandWaypoint(rel, "trunk", vel)
            w_stop = HandWaypoint(stop, "trunk")
            i = task.index
            self.add(h, HandSegment(task.start, t_wind, self.current(h), w_wind, i, "windup"))
            self.add(h, HandSegment(t_wind, t_release, w_wind, w_rel, i, "accelerate"))
            self.add(h, HandSegment(t_release, t_follow, w_rel, w_stop, i, "follow"))
            self.add(h, HandSegment(t_follow, task.end, w_stop, default_waypoint(h), i, "return"))
        self._close_hold(hold, task, t_release, "throw")
        # Planned release state of the object's centre, for its landing point.
        bx, by, byaw, bvx, bvy, bwz = self.trunk.pose_at(t_release)
        c, s = math.cos(byaw), math.sin(byaw)
        r = (k.CARRY_FORWARD + off * ux, off * uy, k.CARRY_HEIGHT + off * uz)
        rwx, rwy = c * r[0] - s * r[1], s * r[0] + c * r[1]
        p = (bx + rwx, by + rwy, self.trunk.height + r[2])
        v = (c * vx - s * vy + bvx - bwz * rwy, s * vx + c * vy + bvy + bwz * rwx, vz)
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
                make_track("L", default_waypoint(0), self.segments[0]),
                make_track("R", default_waypoint(1), self.segments[1]),
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


def _beside(p: Vec3, d: float, lx: float, ly: float) -> Vec3:
    """p moved horizontally by d along the unit vector (lx, ly)."""
    return (p[0] + d * lx, p[1] + d * ly, p[2])


def _along(p: Vec3, d: float, u: Vec3) -> Vec3:
    """p moved by d along the unit vector u."""
    return (p[0] + d * u[0], p[1] + d * u[1], p[2] + d * u[2])


def build_manipulation(
    tasks: tuple[PlannedTask, ...], scenario: Scenario, trunk: TrunkPath
) -> ManipulationPlan:
    """Hand tracks, contacts, object holds and targets for the sorted planned tasks."""
    b = _Builder(scenario, trunk)
    for task in tasks:
        if task.action == "pick":
            b.pick(task)
        elif task.action == "drop":
            b.drop(task)
        elif task.action == "throw":
            b.throw(task)
    return b.finish()
