"""The compiled plan: what the controller evaluates every tick and at every MPC sample.

All times in s from the simulation start, world frame, SI units, radians. Feet and hands are
named "L"/"R" (or 0/1). Vectorised methods take an array of times (n,) and cost a few
`searchsorted` calls; scalar methods (`*_at`, `swing_phase`, ...) use `bisect` on plain lists.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt

from locoplan.plan.events import PlanEvent
from locoplan.plan.export import plan_to_dict
from locoplan.plan.footholds import Footholds
from locoplan.plan.gait import ContactSchedule, SwingPhase, side_index
from locoplan.plan.hands import BasePose
from locoplan.plan.manipulation import HAND_NAMES, ManipulationPlan, ObjectHold, ObjectTarget
from locoplan.plan.robot_geometry import HECTOR_GEOMETRY, PlanGeometry
from locoplan.plan.tasks import PlannedTask
from locoplan.plan.trunk import TrunkPath, TrunkReference, TrunkState

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]


class HandTargets(NamedTuple):
    """Hand targets at one instant, world frame: positions (3,) m and velocities (3,) m/s."""

    p_L_world: FloatArray
    p_R_world: FloatArray
    v_L_world: FloatArray
    v_R_world: FloatArray

    @property
    def positions(self) -> FloatArray:
        """Both positions stacked (2, 3): rows left, right."""
        return np.stack((self.p_L_world, self.p_R_world))

    @property
    def velocities(self) -> FloatArray:
        """Both velocities stacked (2, 3): rows left, right."""
        return np.stack((self.v_L_world, self.v_R_world))


@dataclass(frozen=True, slots=True, eq=False)
class ObjectReference:
    """Planned object load at n times: `held` (n,) bool (sigma_e), `mass` (n,) kg held in total,
    `position` (n, 3) m world: the held object's planned centre (along the planned trunk
    reference), or the planned trunk position where nothing is held (so r_e = 0 there)."""

    held: BoolArray
    mass: FloatArray
    position: FloatArray


@dataclass(frozen=True, slots=True, eq=False)
class Plan:
    """A compiled scenario. Build it with `locoplan.plan.compile_plan`.

    `tasks`: sorted by planned start; `t_end`: simulation end (s); `end_shift`: how much
    quasi-static re-timing moved the end (s, 0 for dynamic); `gait_period`, `gait_swing`: the
    scenario's nominal gait (each locomotion task's own fit is in `contacts.blocks`);
    `footprints`: each fixture's footprint on the floor as (x, y, yaw, half_x, half_y) (m, rad,
    world), where no foot may stand or land (fixtures are solid from the floor up);
    `notes`: what the planner changed in the script's timing and why (one sentence each);
    `geometry`: the robot figures it was planned with (its `base_height` and `foot_width`
    are the plan's own).
    """

    scenario_name: str
    strategy: str
    tasks: tuple[PlannedTask, ...]
    t_end: float
    end_shift: float
    base_height: float
    foot_width: float
    gait_period: float
    gait_swing: float
    contacts: ContactSchedule
    footholds: Footholds
    trunk: TrunkPath
    manipulation: ManipulationPlan
    events: tuple[PlanEvent, ...]
    footprints: tuple[tuple[float, float, float, float, float], ...] = ()
    notes: tuple[str, ...] = ()
    geometry: PlanGeometry = HECTOR_GEOMETRY

    # --- feet (sigma_C1, sigma_C2) ---------------------------------------------------------
    def foot_stance(self, foot: int | str, t: float | npt.ArrayLike) -> bool | BoolArray:
        """Whether the foot is in stance at t (scalar -> bool, array (n,) -> (n,) bool)."""
        return self.contacts.in_stance(foot, t)

    def contact_flags(self, times: npt.ArrayLike) -> BoolArray:
        """Foot stance flags (n, 2) bool at `times` (n,): columns left, right."""
        return self.contacts.flags(times)

    def swing_phase(self, foot: int | str, t: float) -> SwingPhase | None:
        """The foot's swing in progress at t (lift-off, touchdown, phase), or None in stance."""
        return self.contacts.swing_phase(foot, t)

    def next_touchdown(self, foot: int | str, t: float) -> float | None:
        """Touchdown time of the current swing, else of the next one, else None (s)."""
        return self.contacts.next_touchdown(foot, t)

    def next_liftoff(self, foot: int | str, t: float) -> float | None:
        """First lift-off strictly after t, or None (s)."""
        return self.contacts.next_liftoff(foot, t)

    def stance_intervals(self, foot: int | str) -> tuple[tuple[float, float], ...]:
        """Stance intervals of the foot over [0, t_end] (s)."""
        return self.contacts.stance_intervals(foot, self.t_end)

    def swing_intervals(self, foot: int | str) -> tuple[tuple[float, float], ...]:
        """Swing intervals [lift-off, touchdown) of the foot (s)."""
        return self.contacts.swing_intervals(foot)

    def stance_start(self, foot: int | str, t: float) -> float | None:
        """Touchdown time (s) that starts the foot's stance containing t; during a swing, the
        touchdown ending it; None for the initial stance (no touchdown before t)."""
        return self.contacts.stance_start(foot, t)

    def stance_starts(self, foot: int | str, times: npt.ArrayLike) -> FloatArray:
        """`stance_start` at each time (n,) -> (n,) s, NaN for the initial stance."""
        return self.contacts.stance_starts(foot, times)

    def gait_period_at(self, t: float) -> float:
        """Gait period (s) of the locomotion task running at t, else the scenario's nominal."""
        block = self.contacts.block_at(t)
        return self.gait_period if block is None else block.period

    def footholds_at(self, times: npt.ArrayLike) -> FloatArray:
        """Nominal footholds (n, 2, 3) m world: the stance position, or the planned touchdown
        point during a swing."""
        return self.footholds.at(times)

    def foothold_at(self, foot: int | str, t: float) -> FloatArray:
        """Nominal foothold (3,) of one foot at t (m, world)."""
        return self.footholds.foothold_at(foot, t)

    # --- trunk -----------------------------------------------------------------------------
    def trunk_reference(self, times: npt.ArrayLike) -> TrunkReference:
        """Trunk reference at `times` (n,)."""
        return self.trunk.evaluate(times)

    def trunk_reference_at(self, t: float) -> TrunkState:
        """Trunk reference at one time (scalar fast path)."""
        return self.trunk.state_at(t)

    @property
    def final_pose(self) -> tuple[float, float, float]:
        """Trunk (x, y, yaw) after every locomotion task (m, rad)."""
        return self.trunk.end_pose()

    # --- hands (sigma_H1, sigma_H2) --------------------------------------------------------
    def hand_targets_at(
        self,
        t: float,
        base_position: npt.ArrayLike,
        base_yaw: float,
        base_velocity: npt.ArrayLike | None = None,
        base_yaw_rate: float | None = None,
    ) -> HandTargets:
        """Hand targets at t for the given trunk pose (origin (3,) m and yaw rad, world).

        Targets in the trunk frame follow this pose; targets in the world stay put. Velocities
        add the trunk's motion: `base_velocity` (3,) m/s and `base_yaw_rate` rad/s, by default
        the planned ones at t.
        """
        b = self._base_pose(t, base_position, base_yaw, base_velocity, base_yaw_rate)
        pl, vl = self.manipulation.tracks[0].evaluate(t, b)
        pr, vr = self.manipulation.tracks[1].evaluate(t, b)
        return HandTargets(np.array(pl), np.array(pr), np.array(vl), np.array(vr))

    def hand_target_arrays(
        self,
        t: float,
        base_position: npt.ArrayLike,
        base_yaw: float,
        base_velocity: npt.ArrayLike | None = None,
        base_yaw_rate: float | None = None,
    ) -> tuple[FloatArray, FloatArray]:
        """`hand_targets_at` as (positions (2, 3), velocities (2, 3)), rows left, right: one
        array each, for a control loop."""
        b = self._base_pose(t, base_position, base_yaw, base_velocity, base_yaw_rate)
        pl, vl = self.manipulation.tracks[0].evaluate(t, b)
        pr, vr = self.manipulation.tracks[1].evaluate(t, b)
        return np.array((pl, pr), dtype=float), np.array((vl, vr), dtype=float)

    def hand_target_accelerations(
        self,
        t: float,
        base_position: npt.ArrayLike,
        base_yaw: float,
        base_velocity: npt.ArrayLike,
        base_yaw_rate: float,
    ) -> FloatArray:
        """The hand targets' accelerations (2, 3) (m/s^2, rows left, right) at t with the trunk
        at this pose, moving at its present velocity and yaw rate (`HandTrack.acceleration`)."""
        b = self._base_pose(t, base_position, base_yaw, base_velocity, base_yaw_rate)
        tracks = self.manipulation.tracks
        return np.array((tracks[0].acceleration(t, b), tracks[1].acceleration(t, b)), dtype=float)

    def _base_pose(
        self,
        t: float,
        base_position: npt.ArrayLike,
        base_yaw: float,
        base_velocity: npt.ArrayLike | None,
        base_yaw_rate: float | None,
    ) -> BasePose:
        """The trunk pose and velocity the hand tracks are evaluated against (see
        `hand_targets_at` for the defaults)."""
        if base_velocity is None or base_yaw_rate is None:
            _, _, _, pvx, pvy, pwz = self.trunk.pose_at(t)
            vx, vy, vz = (pvx, pvy, 0.0) if base_velocity is None else _xyz(base_velocity)
            wz = pwz if base_yaw_rate is None else float(base_yaw_rate)
        else:
            vx, vy, vz = _xyz(base_velocity)
            wz = float(base_yaw_rate)
        bx, by, bz = _xyz(base_position)
        return BasePose(bx, by, bz, math.cos(base_yaw), math.sin(base_yaw), vx, vy, vz, wz)

    def hand_active(self, hand: int | str, t: float) -> bool:
        """Whether the hand follows a task target (during its manipulation tasks and while it
        touches an object) rather than just holding the default pose."""
        return self.manipulation.active_intervals[side_index(hand)].contains(t)

    def hand_contact(self, hand: int | str, t: float) -> bool:
        """Whether the hand is in contact with an object at t (sigma_H)."""
        return self.manipulation.contact_intervals[side_index(hand)].contains(t)

    def hand_contact_flags(self, times: npt.ArrayLike) -> BoolArray:
        """Hand contact flags (n, 2) bool at `times` (n,): columns left, right (sigma_H1,
        sigma_H2)."""
        times = np.asarray(times, dtype=float)
        out = np.empty((times.shape[0], 2), dtype=bool)
        out[:, 0] = self.manipulation.contact_intervals[0].contains_array(times)
        out[:, 1] = self.manipulation.contact_intervals[1].contains_array(times)
        return out

    def hand_contact_intervals(self, hand: int | str) -> tuple[tuple[float, float], ...]:
        """Contact intervals [grasp, release) of the hand (s; release inf if never)."""
        return self.manipulation.contact_intervals[side_index(hand)].as_tuples()

    # --- objects (sigma_e) -----------------------------------------------------------------
    @property
    def holds(self) -> tuple[ObjectHold, ...]:
        """Every pick .. release of an object, in pick order."""
        return self.manipulation.holds

    def object_held(self, times: npt.ArrayLike) -> BoolArray:
        """Whether some object's weight is on the robot at each time (n,) -> (n,) bool."""
        return self.manipulation.held_intervals.contains_array(times)

    def held_object(self, t: float) -> str | None:
        """Name of the object held at t (lift-off .. release), or None."""
        for hold in self.manipulation.holds:
            if hold.lift <= t < hold.release:
                return hold.object
        return None

    def held_mass(self, times: npt.ArrayLike) -> FloatArray:
        """Total mass held at each time (n,) kg; F_ext = -mass g along z."""
        times = np.asarray(times, dtype=float)
        out = np.zeros(times.shape[0])
        for hold in self.manipulation.holds:
            out += hold.mass * ((times >= hold.lift) & (times < hold.release))
        return out

    def held_mass_at(self, t: float) -> float:
        """Total mass held at t (kg): scalar `held_mass`."""
        return sum(h.mass for h in self.manipulation.holds if h.lift <= t < h.release)

    def holding_hands(self, t: float) -> tuple[int, ...]:
        """Indices (0 left, 1 right) of the hands carrying an object's weight at t (from its
        lift-off to its release), sorted; empty when nothing is held."""
        hands: set[int] = set()
        for h in self.manipulation.holds:
            if h.lift <= t < h.release:
                hands.update(HAND_NAMES.index(x) for x in h.hands)
        return tuple(sorted(hands))

    def object_target(self, name: str) -> ObjectTarget:
        """Where the object should end up (KeyError for an undeclared name)."""
        return self.manipulation.targets[name]

    def object_reference(self, times: npt.ArrayLike) -> ObjectReference:
        """Planned load at `times` (n,) for the MPC: flags, mass and object centre along the
        planned trunk reference (see `object_positions`)."""
        times = np.asarray(times, dtype=float)
        return ObjectReference(
            self.object_held(times), self.held_mass(times), self.object_positions(times)
        )

    def object_positions(
        self,
        times: npt.ArrayLike,
        base_positions: npt.ArrayLike | None = None,
        base_yaws: npt.ArrayLike | None = None,
    ) -> FloatArray:
        """Where the held object is held (n, 3) m world at `times` (n,): the midpoint of the
        hand targets for the given trunk poses (origins (n, 3) m, yaws (n,) rad; default: the
        planned reference). That is the object's centre when it is gripped at its centre and
        `ObjectHold.grip_height` above it for a box carried through locomotion (it hangs
        level below the grip), and `ObjectHold.grip_behind` further from the robot across the
        line between the hands for a box gripped nearer than its centre. The MPC uses it as
        the point where the object's weight acts: with a vertical force only x and y matter to
        the moment (Model 2); Model 1's combined
        inertia sees the grip height too (a few cm). Where nothing is held: the trunk
        position (so r_e = 0 there). A one-hand hold puts the point half the grip width from
        the hand towards the trunk's centre line (an approximation)."""
        times = np.asarray(times, dtype=float)
        ref = self.trunk.evaluate(times)
        pos_b = ref.position if base_positions is None else np.asarray(base_positions, float)
        yaw_b = ref.yaw if base_yaws is None else np.asarray(base_yaws, float)
        position = np.array(pos_b, dtype=float, copy=True)
        held = self.object_held(times)
        for n in np.flatnonzero(held):
            t = float(times[n])
            hold = next(h for h in self.manipulation.holds if h.lift <= t < h.release)
            yaw = float(yaw_b[n])
            px, py, pz = pos_b[n].tolist()
            vx, vy, vz = ref.velocity[n].tolist()
            b = BasePose(
                px, py, pz, math.cos(yaw), math.sin(yaw), vx, vy, vz, float(ref.yaw_rate[n])
            )
            pts = [
                np.array(self.manipulation.tracks[HAND_NAMES.index(h)].evaluate(t, b)[0])
                for h in hold.hands
            ]
            if len(pts) == 2:
                position[n] = 0.5 * (pts[0] + pts[1])
                if hold.grip_behind > 0.0:
                    # The centre lies across the grip line, away from the robot (the left
                    # hand is on the approach's left): `ObjectHold.grip_behind`.
                    dx, dy = float(pts[0][0] - pts[1][0]), float(pts[0][1] - pts[1][1])
                    norm = math.hypot(dx, dy)
                    if norm > 1e-9:
                        position[n, 0] += hold.grip_behind * dy / norm
                        position[n, 1] -= hold.grip_behind * dx / norm
            else:
                side = 1.0 if hold.hands[0] == "L" else -1.0
                y_axis = np.array([-math.sin(yaw), math.cos(yaw), 0.0])
                position[n] = pts[0] - side * hold.half_width * y_axis
        return position

    # --- export ----------------------------------------------------------------------------
    def to_dict(self, reference_dt: float = 0.02) -> dict[str, Any]:
        """JSON-ready description of the plan (see `locoplan.plan.export.plan_to_dict`)."""
        return plan_to_dict(self, reference_dt)


def _xyz(v: Any) -> tuple[float, float, float]:
    return float(v[0]), float(v[1]), float(v[2])
