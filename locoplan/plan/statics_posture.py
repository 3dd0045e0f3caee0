"""The postures of the static analysis (`locoplan.plan.statics`): a standing pose holding a
load, its inverse kinematics with pinocchio and the statics terms of the resulting posture.

Everything comes from the `RobotDescription`: the kinematics and masses of its MJCF through
pinocchio, the joint ranges, the sole and hand frames, the foot's toe and heel, the nominal
pose (whose soles, moved down onto z = 0, are the stance). Trunk upright; joints in no limb
and the arms of hands that hold nothing stay at their nominal angles.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from locoplan.robot.arm_range import narrowed_bounds, working_range
from locoplan.robot.description import RobotDescription
from locoplan.robot.pinocchio_model import PinocchioRobot

FloatArray = NDArray[np.float64]
Vec3 = tuple[float, float, float]

GRAVITY = 9.81  # m/s^2
# Inverse kinematics: residual accepted as reached (m, rad), iteration cap, damping (m).
IK_TOL = 1e-7
IK_ITERATIONS = 60
IK_DAMPING = 1e-3
# The retry of a target the full steps did not reach (`StancePostures.arms`): steps of at most
# IK_SMALL_STEP rad per joint, IK_SMALL_ITERATIONS of them (enough to swing an arm across its
# whole range: 300 x 0.05 rad = 15 rad).
IK_SMALL_STEP = 0.05
IK_SMALL_ITERATIONS = 300
# The damping (m) and step (IK_SMALL_STEP) of a step solved without an elbow held at its
# working bound (`StancePostures._dls`): the arm is then within 0.1 rad of straight, the
# shoulder yaw turns it about its own length and moves the hand 3 cm per rad, and at
# IK_DAMPING full steps threw the arm against its limits (H1 envelope seed 41011,
# standing-hold-005: 0.21 m reported out for a point 0.04 m beyond reach).
IK_BLOCKED_DAMPING = 0.02
# A hand or sole is called out of reach beyond this residual (m): the hands track within 2 cm.
REACH_TOL = 1e-3
# Tolerance (m) of the bisection on the legs' largest shift.
LEG_REACH_TOL = 2.5e-4
_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True, slots=True)
class HeldPose:
    """A standing pose holding a load: trunk origin `trunk_height` (m) above the soles; hand
    points `p_hands_trunk` (m, relative to the trunk origin, trunk axes x forward, y left,
    z up), one per holding hand in `hands` (0 left, 1 right)."""

    trunk_height: float
    hands: tuple[int, ...]
    p_hands_trunk: tuple[Vec3, ...]

    def __post_init__(self) -> None:
        if not (self.trunk_height > 0.0 and math.isfinite(self.trunk_height)):
            raise ValueError(
                f"trunk_height must be a positive length in m, got {self.trunk_height}"
            )
        if len(self.hands) != len(self.p_hands_trunk) or not self.hands:
            raise ValueError("give one hand point per holding hand, at least one")
        if len(set(self.hands)) != len(self.hands) or not set(self.hands) <= {0, 1}:
            raise ValueError(f"hands must be distinct 0 (left) / 1 (right), got {self.hands}")


@dataclass(frozen=True, slots=True, eq=False)
class StaticTerms:
    """Statics of one posture `q` (nq,): gravity g (nv,), the Jacobians (3k, nv) of the k
    foot contact points (each foot's toe then heel, world axes), the generalized force
    sum_h J_h' w_h (nv,) of 1 kg's weight w split over the holding hands (an external force
    on the robot, like the contact forces), the robot's CoM (3,) and the mean of the holding
    hands (3,), m, world."""

    q: FloatArray
    g: FloatArray
    J_contacts: FloatArray
    load_per_kg: FloatArray
    com: FloatArray
    p_load: FloatArray


class StancePostures:
    """Inverse kinematics of one robot for `HeldPose`s, with the trunk at (-shift, 0, height)
    over the nominal stance. World frame: the soles' plane z = 0, x along the unshifted
    trunk's heading."""

    def __init__(self, desc: RobotDescription) -> None:
        robot = PinocchioRobot(desc)
        self.desc = desc
        # The joints' working range (`working_range`): the controller keeps H1's elbows on
        # the nominal side of the straight arm, so the postures here do too.
        self.q_lower, self.q_upper = working_range(robot)
        # The joints whose working range is narrower than their MJCF range (H1's elbows).
        narrowed_lo, narrowed_hi = narrowed_bounds(desc, self.q_lower, self.q_upper)
        self._walled = np.isfinite(narrowed_lo) | np.isfinite(narrowed_hi)
        self.model = robot.model
        self.data = self.model.createData()
        self.mass = robot.total_mass
        self.q_nominal = robot.nominal_q()
        self.q_nominal[:2] = 0.0
        self._foot_ids = [robot.frame_id(f) for f in desc.foot_frames]
        self._hand_ids = [robot.frame_id(f) for f in desc.hand_frames]
        self._legs = np.concatenate(desc.leg_joint_indices)
        self._arms = [np.asarray(i) for i in desc.arm_joint_indices]
        model, data = self.model, self.data
        pin.framesForwardKinematics(model, data, self.q_nominal)
        self._R_feet = [np.array(data.oMf[f].rotation) for f in self._foot_ids]
        self._p_feet = [np.array(data.oMf[f].translation) * (1.0, 1.0, 0.0) for f in self._foot_ids]
        # Toe and heel of each foot relative to its sole frame, world axes.
        self.r_points = [
            R @ np.array([x, 0.0, 0.0])
            for R in self._R_feet
            for x in (desc.foot_toe, -desc.foot_heel)
        ]
        x_points = [
            float(p[0] + r[0])
            for k, p in enumerate(self._p_feet)
            for r in self.r_points[2 * k : 2 * k + 2]
        ]
        self.support_x = (min(x_points), max(x_points))
        self._shoulders = [model.getJointId(desc.joint_names[arm[0]]) for arm in self._arms]
        self.hip_pitch_joints = robot.hip_pitch_joints()
        self.max_reach = (self._longest_reach(0), self._longest_reach(1))
        q = self.q_nominal.copy()
        q[:3] = 0.0
        pin.framesForwardKinematics(model, data, q)
        # Each arm's first joint with the trunk at the origin (`arms`' frame).
        self._shoulder_points = [np.array(data.oMi[j].translation) for j in self._shoulders]
        self._legs_cache: dict[tuple[float, float], tuple[FloatArray, float]] = {}
        self._arms_cache: dict[
            tuple[tuple[int, ...], tuple[tuple[float, ...], ...]],
            tuple[FloatArray, tuple[float, ...], float],
        ] = {}
        self._leg_reach: dict[float, float] = {}

    def _longest_reach(self, hand: int) -> float:
        """Longest distance (m) from the arm's first joint to its hand within the joint
        ranges: a coordinate-wise sweep of the arm's joints from the nominal pose, twice."""
        model, data = self.model, self.data

        def reach(q: FloatArray) -> float:
            pin.framesForwardKinematics(model, data, q)
            shoulder = data.oMi[self._shoulders[hand]].translation
            return float(np.linalg.norm(data.oMf[self._hand_ids[hand]].translation - shoulder))

        q = self.q_nominal.copy()
        best = reach(q)
        for _ in range(2):
            for j in self._arms[hand]:
                for value in np.linspace(self.q_lower[j], self.q_upper[j], 61):
                    trial = q.copy()
                    trial[7 + j] = value
                    d = reach(trial)
                    if d > best:
                        best, q = d, trial
        return best

    def _dls(
        self,
        q: FloatArray,
        goals: Sequence[tuple[int, FloatArray, FloatArray | None]],
        joints: NDArray[np.intp],
        max_step: float = math.inf,
        iterations: int = IK_ITERATIONS,
    ) -> tuple[FloatArray, FloatArray]:
        """Damped least squares moving `joints` (indices into the joints) so that each frame
        of `goals` (frame id, position, rotation or None) reaches its goal, joint ranges
        clamped, each step's joint change at most `max_step` (rad, largest component);
        returns the posture and each goal's residual (m; with the rotation's rad)."""
        model, data = self.model, self.data
        q = q.copy()
        lo, hi = self.q_lower[joints], self.q_upper[joints]
        residual = np.zeros(len(goals))
        for _ in range(iterations):
            pin.computeJointJacobians(model, data, q)
            pin.updateFramePlacements(model, data)
            errors, rows = [], []
            for k, (fid, p, R) in enumerate(goals):
                placement = data.oMf[fid]
                J = pin.getFrameJacobian(model, data, fid, _LWA)[:, 6 + joints]
                e = p - placement.translation
                if R is None:
                    errors.append(e)
                    rows.append(J[:3])
                    residual[k] = np.linalg.norm(e)
                else:
                    e_rot = pin.log3(R @ placement.rotation.T)
                    errors.append(np.concatenate((e, e_rot)))
                    rows.append(J)
                    residual[k] = math.hypot(np.linalg.norm(e), np.linalg.norm(e_rot))
            if residual.max() < IK_TOL:
                break
            e_all = np.concatenate(errors)
            J_all = np.vstack(rows)
            JJt = J_all @ J_all.T + IK_DAMPING**2 * np.eye(J_all.shape[0])
            dq = J_all.T @ np.linalg.solve(JJt, e_all)
            qj = q[7 + joints]
            blocked = self._walled[joints] & (((qj <= lo) & (dq < 0.0)) | ((qj >= hi) & (dq > 0.0)))
            if blocked.any():
                # An elbow at its working bound that the step pushes further out moves
                # nothing: solve again without it, so that the other joints do what it cannot.
                # Without this, a hand just beyond H1's reach stalled with the elbow at that
                # bound (`working_range`, 0.1 rad short of straight) and reported 0.145 m out
                # instead of 0.023 m (envelope seed 40009, walk-carry-025's grasp). Only for
                # the working bounds: at the MJCF ranges the clamped steps stay as they were
                # measured (HECTOR's static figures; done for all joints, its payload limits
                # moved by up to 10 %).
                J_all[:, blocked] = 0.0
                JJt = J_all @ J_all.T + IK_BLOCKED_DAMPING**2 * np.eye(J_all.shape[0])
                dq = J_all.T @ np.linalg.solve(JJt, e_all)
                biggest = float(np.max(np.abs(dq)))
                if biggest > IK_SMALL_STEP:
                    dq *= IK_SMALL_STEP / biggest
            biggest = float(np.max(np.abs(dq)))
            if biggest > max_step:
                dq *= max_step / biggest
            q[7 + joints] = np.clip(q[7 + joints] + dq, lo, hi)
        return q, residual

    def reach_shortfall(self, pose: HeldPose) -> float:
        """How far (m) the farthest of the pose's hand points lies beyond its arm's longest
        reach from the arm's first joint (negative: within it): a lower bound on the residual
        `arms` reports, without the inverse kinematics (triangle inequality; exact up to how
        far `max_reach`'s sweep falls short of the true longest reach)."""
        return max(
            float(np.linalg.norm(np.asarray(p) - self._shoulder_points[h])) - self.max_reach[h]
            for h, p in zip(pose.hands, pose.p_hands_trunk, strict=True)
        )

    def arms(self, pose: HeldPose) -> tuple[FloatArray, tuple[float, ...], float]:
        """Arm joint angles (in q (nq,), trunk at the origin) for the pose's hand points, each
        hand's residual (m) and the reach margin (m): the smallest of max_reach minus the
        shoulder-to-target distance, or minus the residual of a target out of reach.

        Cached by the hand points (the solve starts from the nominal arms whatever the trunk's
        height): the planner asks for the same points again as it tries a pick's step nearer
        or a later start, and a point out of reach costs a few hundred small steps."""
        key = (pose.hands, tuple(tuple(float(c) for c in p) for p in pose.p_hands_trunk))
        hit = self._arms_cache.get(key)
        if hit is None:
            hit = self._solve_arms(pose)
            if len(self._arms_cache) > 4096:
                self._arms_cache.clear()
            self._arms_cache[key] = hit
        return hit[0].copy(), hit[1], hit[2]

    def _solve_arms(self, pose: HeldPose) -> tuple[FloatArray, tuple[float, ...], float]:
        """`arms` without its cache."""
        q = self.q_nominal.copy()
        q[:3] = 0.0
        goals = [
            (self._hand_ids[h], np.asarray(p, dtype=float), None)
            for h, p in zip(pose.hands, pose.p_hands_trunk, strict=True)
        ]
        joints = np.concatenate([self._arms[h] for h in pose.hands])
        start = q
        q, residual = self._dls(start, goals, joints)
        if residual.max() > REACH_TOL:
            # Full Gauss-Newton steps from the nominal arm can throw an arm against its joint
            # limits, where the clamped steps stall: H1's left arm ended at shoulder pitch
            # -164 deg and roll 178 deg for a point 2-5 cm out of reach and reported it 0.2-0.8
            # m out. Small steps follow the reach down to the nearest posture instead.
            q_small, r_small = self._dls(start, goals, joints, IK_SMALL_STEP, IK_SMALL_ITERATIONS)
            if r_small.max() < residual.max():
                q, residual = q_small, r_small
        margins = []
        for h, p, r in zip(pose.hands, pose.p_hands_trunk, residual, strict=True):
            distance = float(np.linalg.norm(np.asarray(p) - self._shoulder_points[h]))
            margins.append(-float(r) if r > REACH_TOL else self.max_reach[h] - distance)
        return q, tuple(float(r) for r in residual), min(margins)

    def legs(self, height: float, shift: float) -> tuple[FloatArray, float]:
        """Leg joint angles (in q (nq,)) with the trunk at (-shift, 0, height) and the soles
        flat at their stance, and the largest sole residual; cached, warm-started from the
        nearest shift solved at that height."""
        key = (round(height, 9), round(shift, 9))
        hit = self._legs_cache.get(key)
        if hit is not None:
            return hit
        near = [k for k in self._legs_cache if k[0] == key[0]]
        if near:
            q = self._legs_cache[min(near, key=lambda k: abs(k[1] - shift))][0].copy()
        else:
            q = self.q_nominal.copy()
        q[:3] = (-shift, 0.0, height)
        goals = list(zip(self._foot_ids, self._p_feet, self._R_feet, strict=True))
        q, residual = self._dls(q, goals, self._legs)
        if len(self._legs_cache) > 4096:
            self._legs_cache.clear()
        self._legs_cache[key] = (q, float(residual.max()))
        return self._legs_cache[key]

    def leg_reach(self, height: float) -> float:
        """The largest shift back (m) at which the legs still put both soles flat at their
        stance (bisection to LEG_REACH_TOL, cached per height); 0 when they cannot even with
        no shift."""
        key = round(height, 9)
        if key not in self._leg_reach:
            lo, hi = 0.0, height
            if self.legs(height, 0.0)[1] > REACH_TOL:
                hi = 0.0
            elif self.legs(height, hi)[1] <= REACH_TOL:
                lo = hi
            while hi - lo > LEG_REACH_TOL:
                mid = 0.5 * (lo + hi)
                if self.legs(height, mid)[1] <= REACH_TOL:
                    lo = mid
                else:
                    hi = mid
            self._leg_reach[key] = lo
        return self._leg_reach[key]

    def terms(self, arms_q: FloatArray, pose: HeldPose, shift: float) -> StaticTerms:
        """The posture with the arms of `arms_q` and the legs at `shift`, and its statics."""
        q = self.legs(pose.trunk_height, shift)[0].copy()
        arm_joints = 7 + np.concatenate(self._arms)
        q[arm_joints] = arms_q[arm_joints]
        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        rows: list[FloatArray] = []
        for k, fid in enumerate(self._foot_ids):
            J = pin.getFrameJacobian(model, data, fid, _LWA)
            # A point r off the frame origin: v_point = v + omega x r = (J_v - [r]x J_w) v.
            rows.extend(J[:3] - pin.skew(r) @ J[3:] for r in self.r_points[2 * k : 2 * k + 2])
        weight = np.array([0.0, 0.0, -GRAVITY / len(pose.hands)])
        load = np.zeros(model.nv)
        p_load = np.zeros(3)
        for h in pose.hands:
            fid = self._hand_ids[h]
            load += pin.getFrameJacobian(model, data, fid, _LWA)[:3].T @ weight
            p_load += data.oMf[fid].translation / len(pose.hands)
        return StaticTerms(
            q=q,
            g=np.array(pin.computeGeneralizedGravity(model, data, q)),
            J_contacts=np.vstack(rows),
            load_per_kg=load,
            com=np.array(pin.centerOfMass(model, data, q)),
            p_load=p_load,
        )
