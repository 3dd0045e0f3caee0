"""Recovery steps: a step the controller adds when, standing, the robot cannot stop where it is.

The plan's contact schedule has the robot stand between its locomotion tasks. Standing on two
line feet, the centre of pressure can go no further than the support polygon (the convex hull
of the soles); by the linear inverted pendulum, a CoM moving at v comes to rest over a centre
of pressure only while its capture point xi = p + v sqrt(z / g) (z the CoM's height above the
soles) lies inside that polygon (Pratt et al. 2006, "Capture point: a step toward humanoid push
recovery"). When xi leaves it, no force the MPC can plan on the standing feet stops the robot
(braking a CoM past its toes, the MPC lets its vertical forces fall to their minimum and the
trunk sinks): HECTOR pushed with 6 N s standing falls forwards, backwards or sideways
(tests/test_recovery.py), and after releasing a 6 kg box onto its platform it fell backwards
(fresh envelope seed 44021, walk-carry-011, both strategies). A person steps. The
controller steps only with its hands free (`LocoManipulationController._free_to_step` says why).
This module decides that step: which foot, when and where; the controller overlays it on the
plan's schedule for its MPC, its WBC and its swing-foot tracking, and the plan stays as
written.

Which foot: when xi lies beyond both feet sideways, the one on that side (a step across the
other leg is not possible); else the one farther from xi sideways, so that the foot that holds
the weight in the swing is the one xi diverges from least sideways. When: `lead` after the
decision, so that the MPC, which sees the lift-off in its horizon from then on, moves the weight
onto the other foot first. Where: the foot's sole middle (between toe and heel) at the capture
point predicted at touchdown, xi_td = c + (xi - c) exp(omega T), c the centre of pressure
the stance foot holds (the point of its sole nearest xi), omega = sqrt(g / z), T the time to
touchdown; sideways no nearer the stance foot than the nominal stance width (the feet must not
collide), and within `reach` of the stance foot's position along and across (the leg's
kinematic stride).

Square-up steps (`plan_square_up_step`) share the schedule: standing at rest, a foot that the
last step of a walk or turn left far from its nominal place steps back to it before the plan
lifts a foot again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt

from locoplan.control.support import clamp_into_support, convex_hull, foot_segments

FloatArray = npt.NDArray[np.float64]
StepReason = Literal["capture", "square-up"]


@dataclass(frozen=True, slots=True)
class RecoveryStep:
    """Foot `foot` (0 left, 1 right) swings from `liftoff` to `touchdown` (s) to `target`
    (3,), world, with yaw `yaw` (rad). `reason`: "capture" (`plan_recovery_step`) or
    "square-up" (`plan_square_up_step`)."""

    foot: int
    liftoff: float
    touchdown: float
    target: FloatArray
    yaw: float
    reason: StepReason = "capture"


def capture_point(p_com: FloatArray, v_com: FloatArray, time_constant: float) -> FloatArray:
    """The capture point (2,) of a CoM at p_com (3,) moving at v_com (3,): p + v sqrt(z / g),
    `time_constant` = sqrt(z / g) (s)."""
    return np.asarray(p_com[:2] + v_com[:2] * time_constant, dtype=np.float64)


def distance_outside(point: FloatArray, hull: FloatArray) -> float:
    """How far (m) the point (2,) lies outside the convex polygon `hull` (k, 2); 0 inside."""
    return float(np.linalg.norm(point - clamp_into_support(point, hull, 0.0)))


def support_hull(p_feet: FloatArray, yaw_feet: FloatArray, toe: float, heel: float) -> FloatArray:
    """The convex hull (k, 2) of both soles (`support.foot_segments`)."""
    return convex_hull(foot_segments(p_feet, yaw_feet, toe, heel))


def plan_recovery_step(
    t: float,
    xi: FloatArray,
    p_feet: FloatArray,
    yaw_feet: FloatArray,
    yaw_trunk: float,
    toe: float,
    heel: float,
    width: float,
    reach: float,
    time_constant: float,
    lead: float,
    swing: float,
) -> RecoveryStep:
    """The step that catches a capture point `xi` (2,) outside the soles of the feet at
    p_feet (2, 3) with yaws yaw_feet (2,) (rad), decided at t (s): see the module's docstring.
    `yaw_trunk` (rad) is the trunk's yaw (its left is "sideways"), toe and heel (m) the sole's
    length ahead of and behind the foot's point, `width` (m) the nominal distance between the
    feet's points across, `reach` (m) how far the foot may land from the stance foot along and
    across, `time_constant` sqrt(z / g) (s), `lead` and `swing` (s) the time before lift-off
    and the swing's duration."""
    c, s = math.cos(yaw_trunk), math.sin(yaw_trunk)
    left = np.array([-s, c])
    # Across: each foot's and xi's coordinate along the trunk's left.
    y_feet = [float(np.dot(p_feet[k, :2], left)) for k in range(2)]
    y_xi = float(np.dot(xi, left))
    if y_xi > max(y_feet):
        foot = int(np.argmax(y_feet))
    elif y_xi < min(y_feet):
        foot = int(np.argmin(y_feet))
    else:
        # Between the feet: the other foot, nearer across, holds the weight.
        foot = 0 if abs(y_feet[0] - y_xi) >= abs(y_feet[1] - y_xi) else 1
    other = 1 - foot
    # The stance foot's centre of pressure nearest xi, and xi at touchdown from it.
    seg = foot_segments(p_feet[other : other + 1], yaw_feet[other : other + 1], toe, heel)
    a, b = seg[0], seg[1]
    ab = b - a
    u = float(np.clip(np.dot(xi - a, ab) / max(float(np.dot(ab, ab)), 1e-12), 0.0, 1.0))
    cop = a + u * ab
    xi_td = cop + (xi - cop) * math.exp((lead + swing) / time_constant)
    # In the trunk's frame relative to the stance foot: along (x) and across (y, the side of
    # the stepping foot positive).
    side = 1.0 if foot == 0 else -1.0
    rel = xi_td - p_feet[other, :2]
    fwd = np.array([c, s])
    dx = float(np.dot(rel, fwd)) - 0.5 * (toe - heel)
    dy = side * float(np.dot(rel, left))
    dx = float(np.clip(dx, -reach, reach))
    dy = float(np.clip(dy, width, width + reach))
    target = np.zeros(3)
    target[:2] = p_feet[other, :2] + dx * fwd + side * dy * left
    return RecoveryStep(foot, t + lead, t + lead + swing, target, float(yaw_feet[foot]))


class RecoverySchedule:
    """The recovery steps added so far, overlaid on the plan's stance flags."""

    def __init__(self) -> None:
        self.steps: list[RecoveryStep] = []

    def swinging(self, foot: int, t: float) -> RecoveryStep | None:
        """The recovery step foot `foot` is swinging in at t, or None."""
        for st in self.steps:
            if st.foot == foot and st.liftoff <= t < st.touchdown:
                return st
        return None

    def busy(self, t: float, settle: float) -> bool:
        """Whether a recovery step is planned or under way at t, or ended less than `settle`
        (s) before it."""
        return any(t < st.touchdown + settle for st in self.steps)

    def flags(self, times: FloatArray, planned: npt.NDArray[np.bool_]) -> npt.NDArray[np.bool_]:
        """The plan's stance flags (n, 2) at `times` (n,) with the recovery swings taken out."""
        if not self.steps:
            return planned
        out = np.array(planned, dtype=bool, copy=True)
        for st in self.steps:
            out[:, st.foot] &= ~((times >= st.liftoff) & (times < st.touchdown))
        return out

    def stance_starts(self, foot: int, times: FloatArray, planned: FloatArray) -> FloatArray:
        """The plan's stance starts (n,) of foot `foot` at `times` (n,) with each recovery
        touchdown starting a stance of its own (NaN compares False: the initial stance)."""
        out = np.array(planned, dtype=float, copy=True)
        for st in self.steps:
            if st.foot != foot:
                continue
            later = times >= st.liftoff
            replace = later & ~(out > st.touchdown)
            out[replace] = st.touchdown
        return out

    def at_touchdown(self, foot: int, t_td: float) -> RecoveryStep | None:
        """The recovery step of foot `foot` touching down at t_td, or None."""
        for st in self.steps:
            if st.foot == foot and abs(st.touchdown - t_td) < 1e-9:
                return st
        return None


def plan_square_up_step(
    t: float,
    p_feet: FloatArray,
    nominal: FloatArray,
    yaw: float,
    width: float,
    excess: float,
    lead: float,
    swing: float,
) -> RecoveryStep | None:
    """The step that brings back a foot standing far from its nominal place, decided at t (s),
    or None: feet at p_feet (2, 3), their nominal places `nominal` (2, 3) about the standing
    reference (yaw `yaw`, rad; `width` m apart across). The foot whose distance from the
    nominal places' centre exceeds width / 2 the most steps to its nominal place, lifting
    `lead` after t for `swing` (s), if that excess is more than `excess` (m) and the place
    lies at least width / 2 across from the other foot (the feet must not meet).

    Why: the standing reference is where the plan's next lift-off expects the weight, between
    the nominal places; the first single support of the next walk or turn needs the CoM over
    the other foot, width / 2 from there. A foot that the last step of a walk put far off
    (a capture-point step after a walk that arrived too fast) leaves the reference near one
    foot and far from the other, and that lift-off then lifts the loaded foot and asks the
    MPC to carry the weight across the whole, larger distance within its horizon: H1, 0.8 s
    after a turning walk that left the right foot 19 cm off (its sole 34 cm across from the
    reference against the nominal 20), fell in the turn that followed (envelope seed 71027,
    locomotion-034). A person shuffles the foot back first."""
    centre = 0.5 * (nominal[0, :2] + nominal[1, :2])
    far = np.linalg.norm(p_feet[:, :2] - centre, axis=1) - 0.5 * width
    foot = int(np.argmax(far))
    if float(far[foot]) <= excess:
        return None
    other = 1 - foot
    left = np.array([-math.sin(yaw), math.cos(yaw)])
    side = 1.0 if foot == 0 else -1.0
    if side * float(np.dot(nominal[foot, :2] - p_feet[other, :2], left)) < 0.5 * width:
        return None
    target = np.array([nominal[foot, 0], nominal[foot, 1], 0.0])
    return RecoveryStep(foot, t + lead, t + lead + swing, target, yaw, "square-up")
