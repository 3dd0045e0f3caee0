"""Static payload checks of a compiled plan: the carry and place poses of every held object.

For each hold (pick .. release) of the plan, the poses in which the hands bear the object's
weight standing still:
- carry: where the pick leaves the hands (its "carry" segment's end) and, when the hands then
  settle the object in, where they settle it ("settle"); both trunk-frame points. The worse
  of the two (by `StaticModel.ratio_at_centre`) is the hold's carry pose.
- place: at a drop's release, the hands at the place point ("lower" segment's end, world),
  seen from the planned trunk pose at that instant. Throws are not checked at their release
  (the object is accelerated there; the static analysis does not apply).
- grasp: at a pick's lift-off, the hands at the grip points ("grip" segment's end, world, just
  inside the object's sides), seen from the planned trunk pose then; mass 0 (the support
  still bears the object). Its reach and its lift's balance matter: `check_lift` refuses a
  pick whose combined centre of mass, with the object's weight at the grip and the trunk
  leaned back as far as the hands may go, stands past the toes; `check_grasp_reach` refuses
  a pick whose grip points are more than GRASP_TOLERANCE + GRASP_SQUEEZE (4 cm) beyond what
  the arms reach from that trunk pose: the hands then stay more than GRASP_TOLERANCE from
  the object's sides, where the hands close (constants), at full stretch. On envelope seed 777 (200
  scripts, 160 picks; the rule is not fitted to it) five grip points at lift-off were beyond
  reach: by 0.164 and 0.073 m (two transfers whose pick starts early in a long turn: both
  failed, one missing the grasp by 0.114 m; now refused), 0.036 m (a transfer: passed),
  0.020 and 0.009 m (standing holds of 12.2 kg, which failed on its weight, and 2 kg, which
  passed).

Each pose goes through `locoplan.plan.statics` with the object's mass (robot facts from its
description), its weight at the hands' points. A box gripped `ObjectHold.grip_behind` (3 cm)
nearer the robot than its centre has its weight that much further out: not modelled here;
it moves the combined centre of mass by m d / (M + m) (under 1 cm for 8 kg on HECTOR) and
puts a moment m g d (2.4 N m at 8 kg) on the hands, which the palms pass to the arms.
`check_payload` refuses a plan whose static worst torque ratio exceeds 1.0, or whose
combined centre of mass no pelvis shift brings over the feet, with an `infeasible (payload)`
or `infeasible (balance)` `InfeasiblePlanError` located at the pick (carry) or the drop
(place). `payload_margins` gives every pose's full analysis, for `locoplan plan`.

Cost: 3-6 ms per pose for the check (one linear programme at the shift that centres the CoM,
which is an upper bound of the best ratio; the full search runs only when that bound is above
1.0), plus building the robot's model once per process (25 ms).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import numpy.typing as npt

from locoplan.exceptions import RobotDescriptionError
from locoplan.plan import constants as k
from locoplan.plan.errors import InfeasiblePlanError, PlanError
from locoplan.plan.geometry import half_extents
from locoplan.plan.hands import HandSegment, Vec3
from locoplan.plan.manipulation import HAND_NAMES, ObjectHold
from locoplan.plan.robot_geometry import HECTOR_GEOMETRY, PlanGeometry
from locoplan.scenario.model import LOCOMOTION_ACTIONS

FloatArray = npt.NDArray[np.float64]

if TYPE_CHECKING:
    # Imported when first needed (`_model`): statics pulls in pinocchio and, through the
    # robot description, MuJoCo, which importing the plan package must not (the controller
    # imports it and never imports MuJoCo).
    from collections.abc import Callable, Mapping

    from locoplan.plan.plan import Plan
    from locoplan.plan.statics import HeldPose, StaticAnalysis, StaticModel
    from locoplan.scenario.model import FixtureSpec, Scenario

PoseKind = Literal["grasp", "carry", "place"]

# Largest pre-lift lean (m) `pre_lean_room` looks for, and its search step (m): the
# equal-margin share of the shift is at most half the support length (7.5 cm for HECTOR's
# line feet) for every envelope load, and 5 mm is a quarter of the hands' tracking error.
PRE_LEAN_MAX = 0.10
PRE_LEAN_TOL = 0.005
# Time step (s) of the search for a later lift-off that reaches a grasp (refusal advice).
GRASP_REACH_STEP = 0.02
# How much (m) the search trusts `StancePostures.reach_shortfall` (a lower bound on the arms'
# residual) to skip a step's inverse kinematics: a step is skipped only when the bound exceeds
# the allowed residual by this. The bound is exact but for how far the arms' longest-reach
# sweep falls short of the true longest reach; tests/test_statics_posture_reach.py checks it
# against the inverse kinematics on random hand points of both robots. The skip took
# `locoplan validate` of a pick 0.5 m out of reach from 8.8 s (171 steps of inverse
# kinematics) to well under a second.
GRASP_REACH_BOUND_SLACK = 0.02


@dataclass(frozen=True, slots=True)
class PlannedHold:
    """One pose of a plan in which the hands bear `mass` kg of `object`: `kind` "grasp" (at
    the lift-off of the pick `task_index`, mass 0), "carry" (at the end of the pick) or
    "place" (at the release of the drop `task_index`), at `time` (s)."""

    object: str
    mass: float
    kind: PoseKind
    task_index: int
    time: float
    pose: HeldPose


@dataclass(frozen=True, slots=True, eq=False)
class PayloadMargin:
    """A `PlannedHold` and its static analysis; for a grasp pose also its lift's balance
    (`lift_margin`: the object's mass, the trunk leaned back `lean` m as the arms allow)."""

    hold: PlannedHold
    analysis: StaticAnalysis
    lift: LiftMargin | None = None
    lift_mass: float = 0.0
    lean: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready margins (m, kg; None for an infinite ratio or limit)."""
        a = self.analysis
        return {
            "object": self.hold.object,
            "pose": self.hold.kind,
            "task": self.hold.task_index,
            "time": self.hold.time,
            "mass": self.hold.mass,
            "hands_in_trunk": [list(p) for p in self.hold.pose.p_hands_trunk],
            "balanced": a.balanced,
            "torque_ratio": _finite(a.torque_ratio),
            "joint": a.joint or None,
            "com_margin": a.com_margin,
            "reach_margin": a.reach_margin,
            "pelvis_shift": a.shift,
            "payload_limit": _finite(a.payload_limit),
            "lift_margin": None if self.lift is None else self.lift.margin,
            "lift_lean": None if self.lift is None else self.lean,
        }


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


def _segment_end(plan: Plan, hand: int, task: int, label: str) -> HandSegment | None:
    for seg in plan.manipulation.tracks[hand].segments:
        if seg.task_index == task and seg.label == label:
            return seg
    return None


def _in_trunk(plan: Plan, seg: HandSegment, t: float | None = None) -> Vec3:
    """A segment's end point in the planned trunk frame at time t (default its end time)."""
    p = seg.end.point
    if seg.end.frame == "trunk":
        return p
    x, y, yaw, *_ = plan.trunk.pose_at(seg.t1 if t is None else t)
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = p[0] - x, p[1] - y
    return (c * dx + s * dy, -s * dx + c * dy, p[2] - plan.trunk.height)


def _pose(
    plan: Plan, hold: ObjectHold, task: int, label: str, at: float | None = None
) -> tuple[HeldPose, float] | None:
    """The hands' points at the end of the segments `label` of `task` in the planned trunk
    frame at time `at` (default each segment's end), and the latest of those ends (s)."""
    from locoplan.plan.statics import HeldPose

    hands = tuple(HAND_NAMES.index(h) for h in hold.hands)
    segments = [_segment_end(plan, h, task, label) for h in hands]
    if any(seg is None for seg in segments):
        return None
    points = tuple(_in_trunk(plan, seg, at) for seg in segments if seg is not None)
    t = max(seg.t1 for seg in segments if seg is not None)
    return HeldPose(plan.trunk.height, hands, points), t


def _hold_poses(plan: Plan, hold: ObjectHold, model: StaticModel | None) -> list[PlannedHold]:
    """The carry pose (with `model`, the worse of the pick's end and the settled pose; else
    both) and, for a drop, the place pose of one hold of `plan`. An object pulled in after
    the pick's end (a "pull" segment: carried through locomotion) is held where the pull
    ends; where the pick ends it only passes, so that pose is not analysed."""
    poses = {lab: _pose(plan, hold, hold.pick_task, lab) for lab in ("carry", "settle", "pull")}
    carries = []
    for label in ("pull",) if poses["pull"] is not None else ("carry", "settle"):
        found = poses[label]
        if found is not None:
            pose, t = found
            carries.append(PlannedHold(hold.object, hold.mass, "carry", hold.pick_task, t, pose))
    if model is not None and len(carries) > 1:
        worst = max(carries, key=lambda c: model.ratio_at_centre(c.pose, c.mass))
        carries = [worst]
    out = carries
    if hold.release_kind == "drop" and hold.release_task is not None:
        found = _place_pose(plan, hold)
        if found is not None:
            pose, t = found
            out.append(PlannedHold(hold.object, hold.mass, "place", hold.release_task, t, pose))
    return out


def _place_pose(plan: Plan, hold: ObjectHold) -> tuple[HeldPose, float] | None:
    """The place pose of a dropped hold (at its release): the "lower" segment's end raised
    by DROP_PRESS, where the object rests on its support (the lowering aims that far below
    it; the hands stop where the support carries the object)."""
    assert hold.release_task is not None
    found = _pose(plan, hold, hold.release_task, "lower")
    if found is None:
        return None
    pose, t = found
    points = tuple((p[0], p[1], p[2] + k.DROP_PRESS) for p in pose.p_hands_trunk)
    return replace(pose, p_hands_trunk=points), t


def _grasp_pose(plan: Plan, hold: ObjectHold) -> PlannedHold | None:
    found = _pose(plan, hold, hold.pick_task, "grip")
    if found is None:
        return None
    pose, t = found
    return PlannedHold(hold.object, 0.0, "grasp", hold.pick_task, t, pose)


def planned_holds(plan: Plan, model: StaticModel | None = None) -> tuple[PlannedHold, ...]:
    """The grasp pose, the carry pose (with `model`, the worse of the pick's end and the
    settled pose; else both) and the place pose of every hold of `plan`, in pick order."""
    out: list[PlannedHold] = []
    for hold in plan.holds:
        grasp = _grasp_pose(plan, hold)
        out.extend(([grasp] if grasp is not None else []) + _hold_poses(plan, hold, model))
    return tuple(out)


def with_pre_leans(plan: Plan, robot: str) -> Plan:
    """`plan` with each hold's `pre_lean` set from the arms' reach at its grasp
    (`pre_lean_room`)."""
    if not plan.holds:
        return plan
    model = _model(robot)
    holds = []
    for hold in plan.holds:
        grasp = _grasp_pose(plan, hold)
        room = pre_lean_room(model, grasp.pose) if grasp is not None else 0.0
        holds.append(replace(hold, pre_lean=room))
    return replace(plan, manipulation=replace(plan.manipulation, holds=tuple(holds)))


def equal_margin_share(size: npt.ArrayLike, offset: float | npt.ArrayLike) -> FloatArray:
    """The equal-margin share beta (same shape as `size`) of a held load's CoM shift of size
    `size` (m): beta = 1/2 + offset / size clipped to [0, 1], `offset` (m) how far the robot's
    own CoM stands ahead of the middle of its feet's support; 1/2 for a zero size. Leaning
    back by beta s leaves the unloaded robot and the loaded one equal margins to the heel and
    the toe (`locoplan.control.controller`'s `_lean_share`, which uses it)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        beta = 0.5 + np.asarray(offset, dtype=float) / np.asarray(size, dtype=float)
    # NaN (0 / 0) is 1/2; +-inf clip to 1 and 0. (np.where, np.minimum and np.maximum: the
    # controller calls this twice per MPC update, and np.nan_to_num with np.clip cost 15 us.)
    beta = np.where(beta != beta, 0.5, beta)
    return np.asarray(np.minimum(np.maximum(beta, 0.0), 1.0), dtype=float)


def lift_lean(model: StaticModel, pose: HeldPose, mass: float) -> float:
    """How far (m) the robot leans back before a lift-off of `mass` kg gripped in the grasp
    `pose`: the controller's equal-margin share of the load shift (`locoplan.control.
    controller._pre_lean`, `_lean_share`), beta s with s = m_o d / (m + m_o), d the hands'
    midpoint ahead of the robot's CoM, and beta the `equal_margin_share` for the CoM's offset
    from the middle of the feet's support along x, in the grasp posture."""
    arms_q, _, _ = model.postures.arms(pose)
    terms = model.postures.terms(arms_q, pose, 0.0)
    ahead = float(terms.p_load[0] - terms.com[0])
    s = mass / (model.mass + mass) * ahead
    if s <= 0.0:
        return 0.0
    middle = 0.5 * (model.support_x[0] + model.support_x[1])
    return float(equal_margin_share(s, float(terms.com[0]) - middle)) * s


def behind_grips(plan: Plan, scenario: Scenario) -> frozenset[str]:
    """The objects of `plan` (compiled from `scenario`) to grip GRIP_BEHIND_CENTRE nearer the
    robot than their centre and to raise straight up before pulling them in
    (`manipulation`, RAISE_UP_SHARE): those held by both hands, gripped above their centre
    (carried through locomotion) to a drop, whose grasp leaves the arms less room to lean back
    (`pre_lean_room`) than the lift's lean (`lift_lean`) by more than the robot's grasp
    tolerance (`PlanGeometry.grasp_tolerance`: how far the hands may be off the points they
    track; a shortfall within it the hands' tracking absorbs).

    Why: at their grasp the arms are at full stretch, the elbows on their joint limit, so the
    arms are rigid rods, and the lean back before the lift-off pulled the box across its
    table through them while it still rested there: 30-146 N towards the robot at the hands
    while they carried 0-25 N of its weight, and the reaction drew the trunk 18-21 cm forward
    in 0.3 s (envelope seed 62021, walk-carry-010, -012, -027: 7.4-7.6 kg 0.35-0.38 m out on
    0.40-0.42 m tables, fell in both strategies). Gripped nearer, the arms have the room;
    raised straight up first, the box is not pulled in before it has left its table (it
    leaves 0.09-0.18 s after the planned lift-off). Only these objects: gripped nearer than
    its centre, a box hangs with its weight's moment about the grip line held by the palms'
    friction (`locoplan.sim.grasp`), which leaves less for the swing of the turns; for every
    carried box to a drop, an H1 parcel gripped off its centre already (a right turn's pick,
    tests/test_h1_transfer.py) swung to 28 deg instead of 21, and one HECTOR transfer of seed
    63021 left its parcel off its platform. The shortfalls, lean less room: 5.3-6.1 cm for the
    three falls above and 63021's transfer-041 (5.77 kg, fell in both strategies without the
    grip, placed with it), 2.4 cm for that lost transfer (-021), 1.3 cm for an H1 transfer
    that the grip lost (seed 57027, transfer-020, 3.38 kg not placed), 1.5-1.7 cm for two
    62021 walk-carries that succeed either way: the grasp tolerance (3 cm HECTOR, 4.3 cm H1)
    keeps the first and leaves the rest as they were."""
    if not plan.holds:
        return frozenset()
    model: StaticModel | None = None
    out = set()
    for hold in plan.holds:
        if hold.grip_height <= 0.0 or hold.release_kind != "drop" or len(hold.hands) != 2:
            continue
        grasp = _grasp_pose(plan, hold)
        if grasp is None:
            continue
        model = model or _model(scenario.robot)
        short = lift_lean(model, grasp.pose, hold.mass) - pre_lean_room(model, grasp.pose)
        if short > plan.geometry.grasp_tolerance:
            out.add(hold.object)
    return frozenset(out)


def centre_grips(plan: Plan, scenario: Scenario) -> frozenset[str]:
    """The objects of `plan` (compiled from `scenario`) to grip at their centre instead of
    `grip_height` above it: those gripped above their centre whose carry pose the arms cannot
    reach (reach margin r < 0, `StaticPostures.arms`) and which, held where the hands stop,
    r short, would pass within CENTRE_GRIP_CLEARANCE of the highest fixture they sweep over
    (`ObjectHold.carry_top`), or into it.

    Why: a narrow box keeps the hands close together, and HECTOR's three-joint arms cannot
    bring them close together high up (shoulder roll): with the hands 9.4 cm apart the carry
    pose 0.13 m above the trunk origin is 4.5 cm out of reach, 0.09 m above it 2.5 cm. Boxes
    0.11-0.12 m wide carried over a 0.52-0.54 m target rode 3.0-4.5 cm under their plan,
    their bottom at the target's top, and in the dynamic strategy (the drop in the turn
    towards the target) three were left on the target's edge and not placed (envelope seeds
    53021, 54021, 55021: transfer-043, -054, -039, predicted 1.3 cm into the target to 0.2 cm
    over it; the quasi-static runs of the same plans cleared the edges by a few mm). Gripped
    at its centre the box is carried as high with the hands `grip_height` lower, where the
    arms reach nearer; those three then place their parcels, and the other 15 runs of those
    seeds that the rule changes succeed as before. Only these objects: gripping at its centre
    every object whose carry pose is out of reach and whose carry height a swept fixture sets
    (127 scripts of those seeds, 254 runs) also lost 4 runs, objects predicted 1.7-3.5 cm
    clear (53021 walk-carry-017 and 54021 transfer-020 fell, 55021 transfer-006 missed its
    grasp), and gained one more (55021 transfer-057, 2.5 cm)."""
    if not plan.holds:
        return frozenset()
    model: StaticModel | None = None
    out = set()
    for hold in plan.holds:
        if hold.grip_height <= 0.0 or hold.carry_top <= 0.0:
            continue
        model = model or _model(scenario.robot)
        half_z = half_extents(scenario.objects[hold.object])[2]
        for pose in _hold_poses(plan, hold, model):
            if pose.kind != "carry":
                continue
            _, _, reach = model.postures.arms(pose.pose)
            z = sum(p[2] for p in pose.pose.p_hands_trunk) / len(pose.pose.p_hands_trunk)
            bottom = plan.trunk.height + z - hold.grip_height - half_z
            if reach < 0.0 and bottom + reach - hold.carry_top < k.CENTRE_GRIP_CLEARANCE:
                out.add(hold.object)
    return frozenset(out)


def reachable_hovers(plan: Plan, robot: str) -> dict[int, float]:
    """The drops of `plan` (by task index) whose hover should end later, and when (s).

    A drop's hover holds the object above its place point in the trunk frame planned at the
    hover's end. Let m(t) be the arms' reach margin (`StaticPostures.arms`, negative: out of
    reach) of that pose in the trunk frame planned at t, and m_ref its value once the trunk
    stops (at the end of the turn or walk that the drop overlaps, or at the latest hover end
    the drop's window allows, the window's end less the lowering as planned, if later). A
    drop whose m at the hover's end is below min(m_ref, 0) - HOVER_REACH_SLACK gets the first
    time t*, on a HOVER_SEARCH_STEP grid, at which m comes up to that bound: what the turn
    still to come costs the arms stays within the slack. The builder ends the hover at t*, or
    at the latest end the window allows if t* is later, holding the object then where the
    trunk will have it at t* (so that the lowering, in the world, brings it the rest of the
    way while the trunk turns on).

    Why: a drop may start in the second half of the turn towards its target (issue 12's
    envelope), and the hover (DROP_HOVER_END of the window) holds the object over the place
    point while the turn goes on: where the turn still has far to go the place point is off
    to the side, beyond what HECTOR's three-joint arms reach across the body (envelope seed
    56021, transfer-014: the far hand 0.17 m short at the hover's end, 0.04 m at the latest
    hover end its window allows; the parcel slipped in the near hand, came down on the
    platform 0.3 s before the planned lowering, was dragged round by the turn and fell off).
    Over the dynamic transfers of seeds 53021-56021, 9 of the 22 runs whose hover the arms
    missed by more than 0.1 m failed, against 9 of the 279 whose hover they reached.
    Where the lowering of a heavier object needs the rest of the window the hover cannot
    wait: 56021 transfer-010 (3.6 kg, 0.14 m short, the turn ending 0.5 s after the drop)
    hovered where the trunk will face the conveyor and places its parcel; as the hover was
    timed the parcel turned 60 deg in the hands. A plan compiled anew with these hover ends
    has nothing left to delay."""

    from locoplan.plan.statics import HeldPose

    out: dict[int, float] = {}
    model: StaticModel | None = None
    for hold in plan.holds:
        if hold.release_kind != "drop" or hold.release_task is None:
            continue
        task = plan.tasks[hold.release_task]
        hands = tuple(HAND_NAMES.index(h) for h in hold.hands)
        hovers = [_segment_end(plan, h, task.index, "hover") for h in hands]
        lowers = [_segment_end(plan, h, task.index, "lower") for h in hands]
        pairs = [(a, b) for a, b in zip(hovers, lowers, strict=True) if a and b]
        if len(pairs) != len(hands):
            continue
        model = model or _model(robot)
        t0 = max(hover.t1 for hover, _ in pairs)
        # Until the trunk stops: the end of the locomotion the drop overlaps, or of the
        # drop's window less its lowering.
        latest = task.end - max(lower.t1 - lower.t0 for _, lower in pairs)
        moving = (
            t.end
            for t in plan.tasks
            if t.action in LOCOMOTION_ACTIONS and t.start < task.end and t.end > task.start
        )
        span = min(plan.t_end, max([latest, *moving]))
        steps = int((span - t0) / k.HOVER_SEARCH_STEP + 1e-9)
        if steps < 1:
            continue
        # The pose the plan holds (a plan with these hover ends: nothing left to delay);
        # within the slack of reach it is within the bound below, whatever m_ref.
        held = tuple(hover.end.point for hover, _ in pairs)
        now = model.postures.arms(HeldPose(plan.trunk.height, hands, held))[2]
        if now >= -k.HOVER_REACH_SLACK:
            continue
        margin = _hover_margin(plan, model, hands, pairs)
        step = k.HOVER_SEARCH_STEP
        bound = min(margin(t0 + steps * step), 0.0) - k.HOVER_REACH_SLACK
        if now >= bound:
            continue
        j = next((j for j in range(1, steps) if margin(t0 + j * step) >= bound), steps)
        out[task.index] = t0 + j * step
    return out


def _hover_margin(
    plan: Plan,
    model: StaticModel,
    hands: tuple[int, ...],
    pairs: list[tuple[HandSegment, HandSegment]],
) -> Callable[[float], float]:
    """The arms' reach margin (m) of a drop's hover pose in the trunk frame planned at a
    time t (s), as a function of t (`reachable_hovers`): the hands straight above their place
    points (the "lower" segments' ends, world) at the hover's height (its end, trunk frame;
    `manipulation._Builder._drop_geometry`)."""
    from locoplan.plan.statics import HeldPose

    def margin(t: float) -> float:
        points = tuple(
            (*_in_trunk(plan, lower, t)[:2], hover.end.point[2]) for hover, lower in pairs
        )
        return model.postures.arms(HeldPose(plan.trunk.height, hands, points))[2]

    return margin


def pre_lean_room(model: StaticModel, pose: HeldPose) -> float:
    """How far (m, at most PRE_LEAN_MAX, on a PRE_LEAN_TOL grid) the trunk may move back from
    the grasp pose `pose`, away from the grip points' midpoint (horizontally), with both arms
    still reaching them (`StaticPostures.arms` reach margin >= 0); 0 when they are already at
    full stretch. Why: the controller leans back before the lift-off so that the combined
    centre of mass stays over the feet when the load comes on (`locoplan.control.controller`
    `_pre_lean`); leaning by more than this room stretched the arms past their reach at the
    grasp, the hands closed on the box 5 cm above their grip points and the box hung that
    much lower through the carry (envelope seed 17320, walk-carry-027: 7.99 kg at 0.38 m,
    room 0; it touched its platform 0.7 s before the release and the robot fell backwards)."""
    mx = sum(p[0] for p in pose.p_hands_trunk) / len(pose.p_hands_trunk)
    my = sum(p[1] for p in pose.p_hands_trunk) / len(pose.p_hands_trunk)
    norm = math.hypot(mx, my)
    if norm < 1e-9:
        return 0.0
    ux, uy = mx / norm, my / norm

    def reaches(b: float) -> bool:
        moved = replace(
            pose,
            p_hands_trunk=tuple((p[0] + b * ux, p[1] + b * uy, p[2]) for p in pose.p_hands_trunk),
        )
        # A point beyond the arm's longest reach gives a negative margin whatever the inverse
        # kinematics finds (`StaticPostures.arms`), and finding it there is the slow case (its
        # small-step retry): the bisection below probes such points half the time.
        if model.postures.reach_shortfall(moved) > 0.0:
            return False
        return model.postures.arms(moved)[2] >= 0.0

    if not reaches(0.0):
        return 0.0
    lo, hi = 0.0, PRE_LEAN_MAX
    if reaches(hi):
        return hi
    while hi - lo > PRE_LEAN_TOL:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if reaches(mid) else (lo, mid)
    return lo


def lift_margin(
    model: StaticModel, pose: HeldPose, mass: float, lean: float, slack: float = 0.0
) -> LiftMargin:
    """The lift-off of `mass` kg gripped in the grasp `pose` with the trunk leaned back `lean`
    m (the pelvis shifted back that far, the hands still at the grip: moved as
    `pre_lean_room` moves them) and `slack` m more (the hands then short of the grip by as
    much, the arms held as at `lean`): the combined centre of mass's margin inside the toes,
    the load at the grip."""
    mx = sum(p[0] for p in pose.p_hands_trunk) / len(pose.p_hands_trunk)
    my = sum(p[1] for p in pose.p_hands_trunk) / len(pose.p_hands_trunk)
    norm = math.hypot(mx, my)
    ux, uy = (mx / norm, my / norm) if norm > 1e-9 else (1.0, 0.0)
    moved = replace(
        pose,
        p_hands_trunk=tuple((p[0] + lean * ux, p[1] + lean * uy, p[2]) for p in pose.p_hands_trunk),
    )
    arms_q, _, _ = model.postures.arms(moved)
    load_x = float(model.postures.terms(arms_q, moved, lean).p_load[0])
    robot_x = float(model.postures.terms(arms_q, moved, lean + slack).com[0])
    toe = model.support_x[1]
    combined = (model.mass * robot_x + mass * load_x) / (model.mass + mass)
    return LiftMargin(toe - combined, robot_x, load_x, toe, model.mass)


@dataclass(frozen=True, slots=True)
class LiftMargin:
    """A lift-off's balance by the static model (`lift_margin`): `margin` (m) of the combined
    centre of mass inside the toes (negative: past them), the robot's own CoM `robot_x` and
    the load's point `load_x` (m, along the feet from the sole sites), the toes' `toe` (m) and
    the robot's mass (kg)."""

    margin: float
    robot_x: float
    load_x: float
    toe: float
    robot_mass: float

    def mass_limit(self, tol: float) -> float:
        """The largest load (kg) whose combined CoM stands at most `tol` m past the toes."""
        over = self.load_x - self.toe - tol
        if over <= 0.0:
            return math.inf
        return max(0.0, self.robot_mass * (self.toe + tol - self.robot_x) / over)

    def nearer(self, mass: float, tol: float) -> float:
        """How much nearer (m) a load of `mass` kg would have to be for its combined CoM to
        stand at most `tol` m past the toes (the arms' room held as it is)."""
        goal = ((self.robot_mass + mass) * (self.toe + tol) - self.robot_mass * self.robot_x) / mass
        return max(0.0, self.load_x - goal)


def check_lift(plan: Plan, robot: str) -> None:
    """Raise an `infeasible (lift)` PlanError, located at the pick, for the first hold of
    `plan` whose lift-off the robot `robot` cannot balance: with the trunk leaned back as far
    as the hands may go, the combined centre of mass of robot and load stands past the toes
    (`lift_margin`). As far as the hands may go: where the arms still reach the grip
    (`ObjectHold.pre_lean`, `pre_lean_room`) and the robot's grasp tolerance further
    (`PlanGeometry.grasp_tolerance`, HECTOR 3 cm: how far the hands may be off the points
    they track; the grasp closes where they are).

    Why: the carry pose's check (`check_payload`) holds the load where the hands carry it, and
    shifts the pelvis back with the hands; at the lift-off the hands are at the grip on the
    table, so the pelvis can go back only as far as the arms reach. A heavy load far out then
    cannot leave its table: the robot leans onto its toes, the hands push the box across the
    top and it stays there, or the robot falls. Measured on the 78 picks of 3.6-13.6 kg with
    the smallest margins of HECTOR envelope seeds 79021 and 81021, each run closed loop and
    its object's height read back (heavy standing picks over 2 s, `compiler.HEAVY_PICK_MIN`):
    of the 18 it refuses, 14 were not held off their table or fell (8.7-13.5 kg blocks, 7.8 kg
    walk-carries) and 4 standing holds of 7.3-10.5 kg, 0.3-1.3 cm past, were held; of those
    it accepts, every standing hold was held, and one 7.86 kg walk-carry 0.6 cm inside fell
    in the fast pull-in before its turn (CHANGELOG, Known limitations). The paper's 14 kg
    hold is 0.5 cm inside (1.1 cm past with the arms' room alone: the planner steps nearer
    first where it can, `compiler._step_in_off_the_tolerance`); issue 12's hold-11kg 2.8 cm
    past."""
    if not plan.holds:
        return
    model = _model(robot)
    slack = plan.geometry.grasp_tolerance
    for hold in plan.holds:
        grasp = _grasp_pose(plan, hold)
        if grasp is None or hold.mass <= 0.0:
            continue
        m = _hold_lift(model, plan, hold, grasp.pose)
        if m.margin >= 0.0:
            continue
        ahead = sum(p[0] for p in grasp.pose.p_hands_trunk) / len(grasp.pose.p_hands_trunk)
        limit = math.floor(m.mass_limit(0.0) * 10.0) / 10.0
        nearer = math.ceil(m.nearer(hold.mass, 0.0) * 100.0) / 100.0
        raise InfeasiblePlanError(
            f"infeasible (lift): lifting '{hold.object}' ({hold.mass:g} kg, gripped "
            f"{ahead:.2f} m ahead of the trunk) puts the centre of mass of robot and load "
            f"{-m.margin:.3f} m past the toes even with the trunk leaned back "
            f"{hold.pre_lean + slack:.3f} m, as far as the hands may be from the grip (the "
            f"arms' reach and the {slack:g} m grasp tolerance; static analysis); lift at most "
            f"{limit:.1f} kg this far out, or place it {nearer:.2f} m nearer the robot",
            hold.pick_task,
            loc=("tasks", hold.pick_task),
        )


def pick_lift_margin(
    plan: Plan, robot: str, pick_task: int, slack: float | None = None, nearer: float = 0.0
) -> LiftMargin | None:
    """The lift-off balance (`lift_margin`) of the hold that task `pick_task` picks, with
    the trunk leaned back the arms' room and `slack` m more (the plan's grasp tolerance
    when None, as `check_lift` judges it); with `nearer` (m), had the robot stood that much
    nearer along the trunk's x at the grasp (the hand points that much nearer, the arms'
    room at them: what a step before the pick would give, `compiler._step_in_for_the_lift`).
    None for no such hold, a massless one, or one without a grasp pose."""
    hold = next((h for h in plan.holds if h.pick_task == pick_task), None)
    if hold is None or hold.mass <= 0.0:
        return None
    grasp = _grasp_pose(plan, hold)
    if grasp is None:
        return None
    if slack is None:
        slack = plan.geometry.grasp_tolerance
    model = _model(robot)
    pose, lean = grasp.pose, hold.pre_lean
    if nearer:
        pose = replace(
            pose, p_hands_trunk=tuple((p[0] - nearer, p[1], p[2]) for p in pose.p_hands_trunk)
        )
        lean = pre_lean_room(model, pose)
    return lift_margin(model, pose, hold.mass, lean, slack)


def _hold_lift(model: StaticModel, plan: Plan, hold: ObjectHold, grasp: HeldPose) -> LiftMargin:
    """`hold`'s lift-off from its `grasp` pose, the trunk leaned back as far as the hands may
    go: the arms' room (`ObjectHold.pre_lean`) and `plan`'s grasp tolerance (`check_lift`)."""
    return lift_margin(model, grasp, hold.mass, hold.pre_lean, plan.geometry.grasp_tolerance)


def _model(robot: str) -> StaticModel:
    from locoplan.plan.statics import static_model

    try:
        return static_model(robot)
    except RobotDescriptionError as exc:
        raise PlanError(f"cannot check payloads: {exc}", loc=("robot",)) from exc


def payload_margins(plan: Plan, robot: str) -> tuple[PayloadMargin, ...]:
    """The full static analysis of every grasp, carry and place pose of `plan` for the
    robot `robot` (a name or robot.yaml path), and each grasp's lift (`lift_margin`): about
    70 ms per pose."""
    if not plan.holds:
        return ()
    model = _model(robot)
    holds = {(h.object, h.pick_task): h for h in plan.holds}
    out = []
    for held in planned_holds(plan, model):
        margin = PayloadMargin(held, model.analyse(held.pose, held.mass))
        hold = holds.get((held.object, held.task_index))
        if held.kind == "grasp" and hold is not None and hold.mass > 0.0:
            lean = hold.pre_lean + plan.geometry.grasp_tolerance
            lift = _hold_lift(model, plan, hold, held.pose)
            margin = replace(margin, lift=lift, lift_mass=hold.mass, lean=lean)
        out.append(margin)
    return tuple(out)


def grasp_reach_limit(geometry: PlanGeometry = HECTOR_GEOMETRY) -> float:
    """How far (m) a grip point may lie beyond the arms' reach (module docstring): the
    robot's grasp tolerance (`geometry`'s; HECTOR's GRASP_TOLERANCE) plus GRASP_SQUEEZE."""
    return geometry.grasp_tolerance + k.GRASP_SQUEEZE


def check_grasp_reach(plan: Plan, robot: str) -> None:
    """Raise an `infeasible (reach)` PlanError, located at the pick, for the first pick of
    `plan` whose grip points the robot `robot` cannot reach from the planned trunk pose at
    the lift-off (module docstring), saying when a later start of the pick would reach them
    or else how far out of reach they are."""
    if not plan.holds:
        return
    model = _model(robot)
    for hold in plan.holds:
        grasp = _grasp_pose(plan, hold)
        if grasp is None:
            continue
        residual = _grip_residual(model, grasp.pose)
        limit = grasp_reach_limit(plan.geometry)
        if residual <= limit:
            continue
        task = plan.tasks[hold.pick_task]
        later = _reachable_after(plan, hold, model)
        ahead = max(math.hypot(p[0], p[1]) for p in grasp.pose.p_hands_trunk)
        what = (
            f"infeasible (reach): at the lift-off of '{hold.object}' ({grasp.time:.2f} s) its "
            f"grip points are {residual:.3f} m beyond the arms' reach from the planned trunk "
            f"pose (up to {ahead:.2f} m from the trunk's axis; allowed "
            f"{limit:.2f} m: the hands close within {plan.geometry.grasp_tolerance:.2f} m "
            "of its sides)"
        )
        if later is not None:
            advice = (
                f"start the pick at {task.start + later:.2f} s or later (the trunk then "
                "faces the object), or place the object nearer the robot"
            )
        else:
            advice = "place the object nearer the robot or walk up to it first"
        err = InfeasiblePlanError(
            f"{what}; {advice}", hold.pick_task, loc=("tasks", hold.pick_task)
        )
        err.excess = residual - limit
        raise err


def planned_grasp(plan: Plan, pick_task: int, robot: str) -> tuple[float, float] | None:
    """The lift-off time (s) of the pick `pick_task` and how far (m) the arms of `robot`
    miss its grip points then from the planned trunk pose (None: no such pick)."""
    for hold in plan.holds:
        if hold.pick_task != pick_task:
            continue
        grasp = _grasp_pose(plan, hold)
        if grasp is None:
            return None
        return grasp.time, _grip_residual(_model(robot), grasp.pose)
    return None


# How far (m) inside the edge of its target's top an object released short of its planned
# place must still have its centre: the hands' closing tolerance (GRASP_TOLERANCE, what they
# may be off the points they track). Without it a centre that ended at the edge was allowed:
# package-transfer.yaml's conveyor moved to x = 0.53 / 0.55 / 0.57 / 0.59 m (misses of 5.6,
# 7.4, 9.3 and 11.2 cm, the centre 12 cm inside): placed, placed, not placed, not placed;
# envelope seed 5000 transfer-046 (2.2 cm left inside): not placed. This slack refuses the
# last three and accepts the first two. HECTOR's: the plan's robot's grasp tolerance
# (`PlanGeometry.grasp_tolerance`) is what `check_place_reach` uses.
PLACE_SLACK = k.GRASP_TOLERANCE


def check_place_reach(plan: Plan, robot: str, fixtures: Mapping[str, FixtureSpec]) -> None:
    """Raise an `infeasible (reach)` PlanError, located at the drop, for the first drop onto
    a fixture of `fixtures` whose place points (the hands' points at the release) the robot
    `robot` misses from the planned trunk pose by more than the object could fall short and
    still rest on the fixture: the distance from its planned centre to the nearest edge of
    the fixture's top less PLACE_SLACK (at least the grasp's allowance,
    `grasp_reach_limit`). Nothing else refuses such a target: the format takes any fixture
    position, and the hands' paths towards it are planned whatever their length (a conveyor
    1000 km away validated as ok).
    Standing holds put back on their table miss by up to 5.5 cm (envelope seeds 31337,
    90210) and are placed: their centre is 14 cm inside the table's edge."""
    if not plan.holds:
        return
    model = _model(robot)
    for hold in plan.holds:
        if hold.release_kind != "drop" or hold.release_task is None:
            continue
        task = plan.tasks[hold.release_task]
        fixture = fixtures.get(task.onto) if task.onto else None
        found = _place_pose(plan, hold)
        if fixture is None or found is None:
            continue
        pose, t = found
        residual = _grip_residual(model, pose)
        # This hold's planned place (an object may be picked and dropped more than once).
        cx, cy, _ = plan.object_positions(np.array([hold.release - 1e-6]))[0]
        inside = _inside_top(fixture, float(cx), float(cy))
        slack = plan.geometry.grasp_tolerance
        allowed = max(grasp_reach_limit(plan.geometry), inside - slack)
        if residual <= allowed:
            continue
        ahead = max(math.hypot(p[0], p[1]) for p in pose.p_hands_trunk)
        err = InfeasiblePlanError(
            f"infeasible (reach): at the release of '{hold.object}' onto '{task.onto}' "
            f"({t:.2f} s) the hands' points are {residual:.3f} m beyond the arms' reach from "
            f"the planned trunk pose (up to {ahead:.2f} m from the trunk's axis; allowed "
            f"{allowed:.2f} m: the object's planned centre lies {inside:.2f} m inside the "
            f"edge of the fixture's top and must stay {slack:.2f} m inside it); put the "
            "target nearer the robot or walk up to it before the drop",
            hold.release_task,
            loc=("tasks", hold.release_task),
        )
        err.excess = residual - allowed
        raise err


def _inside_top(fixture: FixtureSpec, x: float, y: float) -> float:
    """How far (m) the point (x, y) lies inside the edges of `fixture`'s top (negative:
    outside)."""
    u, v = fixture.local_xy(x, y)
    return min(fixture.size[0] / 2.0 - abs(u), fixture.size[1] / 2.0 - abs(v))


def _grip_residual(model: StaticModel, pose: HeldPose) -> float:
    """The largest distance (m) by which the arms miss the pose's hand points."""
    _, residual, _ = model.postures.arms(pose)
    return max(residual)


def _reachable_after(plan: Plan, hold: ObjectHold, model: StaticModel) -> float | None:
    """The least delay (s, on a GRASP_REACH_STEP grid) of a pick's lift-off after which the
    planned trunk pose reaches its (world-fixed) grip points, up to the plan's end; None if
    none does. An estimate for the refusal's advice: a later pick is planned afresh."""
    found = _pose(plan, hold, hold.pick_task, "grip")
    if found is None:
        return None
    t0 = found[1]
    steps = int((plan.t_end - t0) / GRASP_REACH_STEP)
    limit = grasp_reach_limit(plan.geometry)
    # Poses already found out of reach: where the trunk stands still, every later time gives
    # the same pose, and each costs an inverse-kinematics solve (a standing pick 5 cm out of
    # reach took 300 of them, 15 s, for the same answer).
    tried: set[HeldPose] = set()
    for j in range(1, steps + 1):
        later = _pose(plan, hold, hold.pick_task, "grip", at=t0 + j * GRASP_REACH_STEP)
        if later is None or later[0] in tried:
            continue
        tried.add(later[0])
        if model.postures.reach_shortfall(later[0]) > limit + GRASP_REACH_BOUND_SLACK:
            continue
        if _grip_residual(model, later[0]) <= limit:
            return math.ceil(j * GRASP_REACH_STEP * 100.0 - 1e-9) / 100.0
    return None


def check_payload(plan: Plan, robot: str) -> None:
    """Raise an `infeasible (payload)` / `infeasible (balance)` PlanError, located at the
    task, for the first carry or place pose of `plan` that the robot `robot` cannot hold
    statically (module docstring)."""
    if not plan.holds:
        return
    model = _model(robot)
    for held in planned_holds(plan, model):
        if held.kind == "grasp":
            continue
        if model.ratio_at_centre(held.pose, held.mass) <= 1.0:
            continue
        analysis = model.analyse(held.pose, held.mass)
        if analysis.balanced and analysis.torque_ratio <= 1.0:
            continue
        raise InfeasiblePlanError(
            _refusal(held, analysis), held.task_index, loc=("tasks", held.task_index)
        )


def _refusal(held: PlannedHold, a: StaticAnalysis) -> str:
    pose = held.pose
    ahead = sum(p[0] for p in pose.p_hands_trunk) / len(pose.p_hands_trunk)
    where = (
        f"the carry pose of '{held.object}'"
        if held.kind == "carry"
        else f"the place pose of '{held.object}' at its release"
    )
    closer = "hold it closer" if held.kind == "carry" else "place it nearer the robot"
    limit = math.floor(a.payload_limit * 10.0) / 10.0
    advice = f"carry at most {limit:.1f} kg or {closer}"
    if a.balanced:
        return (
            f"infeasible (payload): {held.mass:g} kg exceeds the {limit:.1f} kg that the "
            f"{a.joint} allows in {where} (static analysis: hands {ahead:.2f} m ahead of the "
            f"trunk, worst torque ratio {a.torque_ratio:.2f} at {a.joint}); {advice}"
        )
    if a.com_margin >= 0.0:
        off = "outside the feet's support sideways"
    elif a.com_x > a.support_x[1]:
        off = f"{-a.com_margin:.3f} m ahead of the toes"
    else:
        off = f"{-a.com_margin:.3f} m behind the heels"
    return (
        f"infeasible (balance): in {where} (hands {ahead:.2f} m ahead of the trunk, "
        f"{held.mass:g} kg) the centre of mass of robot and load stays {off} even with the "
        f"pelvis {a.shift:.2f} m back (the most the legs allow: {a.shift_max:.2f} m); {advice}"
    )
