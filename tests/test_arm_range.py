"""The arms' working range (`locoplan.robot.arm_range`) and how the controller and the static
analysis keep to it: H1's elbows stop short of the straight arm on their nominal side,
HECTOR's short of their straight stop; the controller's wall rows (`joint_wall_rows`) stop a joint
at its working bound; the static inverse kinematics reaches a point beyond the arm's reach
with the elbow at that bound instead of stalling there. The closed-loop check is
tests/test_h1_transfer.py::test_h1_pull_in_keeps_the_elbows_on_their_side."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from locoplan.control.controller import joint_wall_rows
from locoplan.plan.statics_posture import HeldPose, StancePostures
from locoplan.robot.arm_range import STRAIGHT_MARGIN, straight_arm_angle, working_range
from locoplan.robot.description import load_robot_description
from locoplan.robot.pinocchio_model import PinocchioRobot


def _reach(robot: PinocchioRobot, hand: int, joint: int, angle: float) -> float:
    """Shoulder (first arm joint) to hand distance (m), the other joints nominal."""
    q = robot.nominal_q()
    q[7 + joint] = angle
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q)
    desc = robot.desc
    first = robot.model.getJointId(desc.joint_names[int(desc.arm_joint_indices[hand][0])])
    hand_p = data.oMf[robot.frame_id(desc.hand_frames[hand])].translation
    return float(np.linalg.norm(hand_p - data.oMi[first].translation))


def test_h1_elbows_stop_short_of_the_straight_arm() -> None:
    robot = PinocchioRobot(load_robot_description("h1"))
    desc = robot.desc
    lower, upper = working_range(robot)
    for hand, side in enumerate("LR"):
        j = desc.joint_names.index(f"{side}_elbow")
        straight = straight_arm_angle(robot, hand, j)
        assert straight is not None
        # The straight arm is the farthest the hand gets: 0.05 rad either side is nearer
        # (by about l1 l2 (1 - cos 0.05) / d = 0.2 mm; asserted > 0 to rounding).
        d0 = _reach(robot, hand, j, straight)
        assert d0 > _reach(robot, hand, j, straight - 0.05) + 1e-5
        assert d0 > _reach(robot, hand, j, straight + 0.05) + 1e-5
        # Inside the MJCF range (-1.25 .. 2.61 rad), near 1.48 rad (the measured value).
        assert desc.q_lower[j] < straight < desc.q_upper[j]
        assert straight == pytest.approx(1.48, abs=0.02)
        # The nominal elbow (0) is below it, so the upper bound moves, the lower does not.
        assert upper[j] == pytest.approx(straight - STRAIGHT_MARGIN, abs=1e-9)
        assert lower[j] == desc.q_lower[j]
    # Every other joint keeps its MJCF range (H1's shoulder roll and yaw move the hand
    # 6-8 cm nearer or farther only: they do not fold the arm).
    others = [i for i, n in enumerate(desc.joint_names) if not n.endswith("elbow")]
    np.testing.assert_array_equal(lower[others], np.asarray(desc.q_lower)[others])
    np.testing.assert_array_equal(upper[others], np.asarray(desc.q_upper)[others])


def test_hector_elbows_stop_short_of_their_straight_stop() -> None:
    """HECTOR's elbow flexes 0..150 deg from the straight arm: the straight arm is the stop at
    0, and the working range starts STRAIGHT_MARGIN above it (the hand 0.5 mm nearer at
    most); every other joint keeps its MJCF range."""
    robot = PinocchioRobot(load_robot_description("hector"))
    desc = robot.desc
    lower, upper = working_range(robot)
    elbows = [desc.joint_names.index(f"{side}_elbow") for side in "LR"]
    for hand, j in enumerate(elbows):
        assert straight_arm_angle(robot, hand, j) == pytest.approx(0.0, abs=1e-12)
        assert desc.q_lower[j] == 0.0
        assert lower[j] == pytest.approx(STRAIGHT_MARGIN, abs=1e-12)
        assert upper[j] == desc.q_upper[j]
        lost = _reach(robot, hand, j, 0.0) - _reach(robot, hand, j, STRAIGHT_MARGIN)
        assert 0.0 < lost < 1e-3
    others = [i for i in range(len(desc.joint_names)) if i not in elbows]
    np.testing.assert_array_equal(lower[others], np.asarray(desc.q_lower)[others])
    np.testing.assert_array_equal(upper, desc.q_upper)


def test_wall_rows_stop_a_joint_at_its_bound() -> None:
    """The wall lets a joint approach its bound no faster than sqrt(2 A d) (A the
    deceleration, d the distance left), reached with time constant tau."""
    A, tau = 50.0, 0.05
    cols = np.array([6, 7], dtype=np.intp)  # joints 0 and 1
    lower, upper = np.array([-1.0, -1.0]), np.array([1.0, 1.0])
    q = np.zeros(9)
    v = np.zeros(8)
    # Joint 0 0.01 rad from its bound, still, asked 50 rad/s^2 outwards: allowed speed
    # sqrt(2 x 50 x 0.01) = 1 rad/s, so (1 - 0) / 0.05 = 20 rad/s^2. Joint 1 at 0, 1 rad
    # away (allowed 10 rad/s, 200 rad/s^2): no row.
    q[7] = 0.99
    qdd = np.zeros(8)
    qdd[6] = qdd[7] = 50.0
    hit, acc = joint_wall_rows(cols, lower, upper, q, v, qdd, A, tau)
    assert hit.tolist() == [6]
    assert acc == pytest.approx([20.0])
    # 0.04 rad away at 3 rad/s: allowed 2 rad/s, so it brakes at (2 - 3) / 0.05 = -20 rad/s^2
    # although the task asks for nothing; 0.25 rad away at the same speed (allowed 5 rad/s)
    # it is left alone (a PD on the bound, kp 100 kd 20, braked there already).
    q[7], v[6] = 0.96, 3.0
    qdd[:] = 0.0
    hit, acc = joint_wall_rows(cols, lower, upper, q, v, qdd, A, tau)
    assert hit.tolist() == [6]
    assert acc == pytest.approx([-20.0])
    q[7] = 0.75
    hit, acc = joint_wall_rows(cols, lower, upper, q, v, qdd, A, tau)
    assert len(hit) == 0
    # Past the bound by 0.01 rad, still: pushed back at -1 rad/s, -20 rad/s^2.
    q[7], v[6] = 1.01, 0.0
    hit, acc = joint_wall_rows(cols, lower, upper, q, v, qdd, A, tau)
    assert hit.tolist() == [6]
    assert acc == pytest.approx([-20.0])
    # The lower bound the same way: joint 1 0.01 rad above -1, asked -50: held to -20.
    q[7] = 0.0
    q[8] = -0.99
    qdd[7] = -50.0
    hit, acc = joint_wall_rows(cols, lower, upper, q, v, qdd, A, tau)
    assert hit.tolist() == [7]
    assert acc == pytest.approx([-20.0])
    # Nothing near a bound: no row.
    q[8] = 0.0
    hit, acc = joint_wall_rows(cols, lower, upper, q, v, qdd, A, tau)
    assert len(hit) == 0 and len(acc) == 0


def test_static_ik_reaches_past_the_elbow_bound_with_the_shoulder() -> None:
    """H1's grasp pose of envelope seed 40009, walk-carry-025 (grip points 0.51 m ahead,
    beyond the arms' reach): the inverse kinematics ends with the elbows at their working
    bound and the hands 2.3 cm short (measured; the MJCF range allowed 2.5 cm). Before the
    bound's joint was taken out of the step it stalled there at 0.145 m and the plan was
    refused for reach."""
    postures = StancePostures(load_robot_description("h1"))
    pose = HeldPose(0.98, (0, 1), ((0.51, 0.103, 0.055), (0.51, -0.104, 0.055)))
    q, residual, margin = postures.arms(pose)
    assert max(residual) < 0.03
    assert margin == pytest.approx(-max(residual))
    for side in "LR":
        j = postures.desc.joint_names.index(f"{side}_elbow")
        assert q[7 + j] <= postures.q_upper[j] + 1e-12


def test_heavy_pull_reads_the_hip_pitch() -> None:
    """The heavy pull-in's leg torque (`compiler._leg_torque`) is the hip pitch's limit: the
    same 33.5 N m as HECTOR's weakest leg joint, and H1's 200 N m, not its 40 N m ankle."""
    from locoplan.plan.compiler import _leg_torque
    from locoplan.plan.statics import static_model

    for robot, names, torque in (
        ("hector", ["L_hip_pitch", "R_hip_pitch"], 33.5),
        ("h1", ["L_hip_pitch", "R_hip_pitch"], 200.0),
    ):
        model = static_model(robot)
        assert [model.desc.joint_names[j] for j in model.postures.hip_pitch_joints] == names
        assert _leg_torque(robot) == pytest.approx(torque)


def test_an_unbounded_side_never_walls() -> None:
    """The controller walls only the narrowed side (-inf / inf on the MJCF side, which
    MuJoCo's limit holds): an elbow folding fast towards its MJCF stop is left alone (a wall
    there braked H1's elbow 1.3 rad early in the tuck and threw the arms about)."""
    cols = np.array([6], dtype=np.intp)
    q = np.zeros(8)
    q[7] = -0.5
    v = np.zeros(7)
    v[6] = -10.0
    qdd = np.full(7, -100.0)
    hit, _ = joint_wall_rows(cols, np.array([-np.inf]), np.array([1.377]), q, v, qdd, 337.0)
    assert len(hit) == 0
