"""The arms' working range: each arm joint's MJCF range, less the far side of a straight arm.

An elbow whose range reaches past the straight arm (H1's: -1.25..2.61 rad, straight at
1.48) can fold the forearm either way. Going through straight is a singularity of the hand's
position task (the hand cannot move along the arm there), and a task-space controller that
tracks a hand target inward from near full reach can cross it and then fold the arm the
wrong way: H1 envelope seed 40009, walk-carry-002 (the box pulled in after its pick): both
elbows crossed straight at 1.5 s, went on to their 2.61 rad stop, the hands ended 10-20 cm
from their targets with the shoulder rolls at their limits and at full torque, and the
robot fell at 3.4 s. Of that seed's 15 falls, 12 had an elbow at its far stop (2.6-2.9 rad)
first; of its 385 other runs none went past 2.01 rad. The static analysis found the same
carry pose with the elbow at -0.36 rad, folded the nominal way.

So the working range stops `STRAIGHT_MARGIN` short of straight on the side of the nominal
angle, for each arm joint that folds the arm: its sweep (the other joints nominal) changes
the distance from the arm's first joint to the hand by more than `FOLD_SHARE` of the
largest distance, with that largest distance strictly inside the range. The controller
keeps the joint inside it (`locoplan.control.controller`), and the static analysis's
inverse kinematics and reach use it (`locoplan.plan.statics_posture`), so that the plan
asks for nothing the controller refuses. Every shoulder joint keeps its MJCF range.

A straight arm at a stop of the range is walled the same way: HECTOR's elbows (0..150 deg
of flexion, straight at 0) work from 0.1 rad. Why: a hand asked for a point beyond reach
(a place the plan accepts short of reach, `payload.check_place_reach`) drove the elbow
onto its stop at 0, where MuJoCo's limit force, which the WBC's model does not have, took
the hand task's push; when the hands then moved back along the straight arms after the
release (the one direction a straight arm cannot move its hand), the WBC relaxed the
trunk's accelerations by up to 94 m/s^2 and 134 rad/s^2 and the robot rose 5 cm on its
legs and fell sideways (HECTOR fresh envelope seed 44021, side-carry-013, place reach
margin -0.021 m, both strategies; both succeed with the wall). The margin costs about
0.5 mm of HECTOR's reach ((1 - cos 0.1) l1 l2 / d).
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from locoplan.robot.description import RobotDescription
from locoplan.robot.pinocchio_model import PinocchioRobot

FloatArray = NDArray[np.float64]

# How far (rad) short of the straight arm the working range of a folding joint stops.
# 0.1 rad (6 deg) costs the hand (1 - cos 0.1) l1 l2 / d = 0.8 mm of reach on H1 (upper
# arm and forearm about 0.3 m each, d 0.6 m) and keeps H1's grasp poses (elbow at most 1.32
# rad over the envelope's picks, straight at 1.48) inside the range.
STRAIGHT_MARGIN = 0.1
# A joint folds the arm when its sweep changes the shoulder-to-hand distance by more than
# this share of the largest: H1's elbow 76 %, HECTOR's 72 %; H1's shoulder roll and yaw,
# whose axes pass 2-6 cm from the shoulder pitch's, 13-15 %.
FOLD_SHARE = 0.5
# Samples of a joint's range to find the straight arm (then refined by golden section to
# about 1e-6 rad).
_SAMPLES = 97
_GOLDEN_STEPS = 40


def straight_arm_angle(robot: PinocchioRobot, hand: int, joint: int) -> float | None:
    """The angle (rad) of arm joint `joint` (index into the joints) of arm `hand` (0 left,
    1 right) at which the arm is straight (the largest shoulder-to-hand distance, the other
    joints nominal; the range's end when it is largest there), or None when the joint does
    not fold the arm."""
    model, desc = robot.model, robot.desc
    lo, hi = float(desc.q_lower[joint]), float(desc.q_upper[joint])
    q = robot.nominal_q()
    data = model.createData()
    first = model.getJointId(desc.joint_names[int(desc.arm_joint_indices[hand][0])])
    hand_id = robot.frame_id(desc.hand_frames[hand])

    def dist(angle: float) -> float:
        q[7 + joint] = angle
        pin.framesForwardKinematics(model, data, q)
        return float(np.linalg.norm(data.oMf[hand_id].translation - data.oMi[first].translation))

    angles = np.linspace(lo, hi, _SAMPLES)
    d = np.array([dist(a) for a in angles])
    i = int(np.argmax(d))
    if d.max() - d.min() <= FOLD_SHARE * d.max():
        return None
    if i in (0, _SAMPLES - 1):
        # Straight at a stop of the range (HECTOR's elbow, straight at 0).
        return float(angles[i])
    a, b = float(angles[i - 1]), float(angles[i + 1])
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    for _ in range(_GOLDEN_STEPS):
        c, e = b - ratio * (b - a), a + ratio * (b - a)
        if dist(c) > dist(e):
            b = e
        else:
            a = c
    return 0.5 * (a + b)


def working_range(robot: PinocchioRobot) -> tuple[FloatArray, FloatArray]:
    """Each joint's working range (lower, upper), rad, (n_joints,) each: the MJCF range, and
    for an arm joint that folds the arm through a straight arm inside its range or at one of
    its stops, the side of the straight arm that holds the nominal angle, `STRAIGHT_MARGIN`
    short of it."""
    desc = robot.desc
    lower = np.asarray(desc.q_lower, dtype=float).copy()
    upper = np.asarray(desc.q_upper, dtype=float).copy()
    for hand, arm in enumerate(desc.arm_joint_indices):
        for j in (int(x) for x in arm):
            straight = straight_arm_angle(robot, hand, j)
            if straight is None:
                continue
            if desc.q_joints_nominal[j] < straight:
                upper[j] = min(upper[j], straight - STRAIGHT_MARGIN)
            else:
                lower[j] = max(lower[j], straight + STRAIGHT_MARGIN)
    return lower, upper


def narrowed_bounds(
    desc: RobotDescription, lower: FloatArray, upper: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The working bounds (`working_range`'s `lower`, `upper`) where they are narrower than
    the MJCF range, -inf / inf where they are the MJCF range (which MuJoCo's joint limit
    holds): what the controller walls, and where the static IK re-solves a blocked step."""
    lo = np.where(lower > np.asarray(desc.q_lower), lower, -np.inf)
    hi = np.where(upper < np.asarray(desc.q_upper), upper, np.inf)
    return lo, hi
