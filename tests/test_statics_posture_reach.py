"""The arms' inverse kinematics of the static analysis (`locoplan.plan.statics_posture`) for
points just out of reach: the reported residual is the distance beyond reach, not an arm
thrown against its joint limits (H1's 4-DoF arms; its full Gauss-Newton steps once reported
0.2-0.8 m for points 2-5 cm out, and refused standing holds H1 completes)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from locoplan.plan.statics_posture import REACH_TOL, HeldPose, StancePostures
from locoplan.robot.description import load_robot_description


@pytest.fixture(scope="module")
def h1() -> StancePostures:
    return StancePostures(load_robot_description("h1"))


def _shoulder(p: StancePostures, hand: int) -> np.ndarray:
    """The shoulder's centre relative to the trunk origin (what HeldPose's points are)."""
    q = p.q_nominal.copy()
    q[:3] = 0.0
    pin.framesForwardKinematics(p.model, p.data, q)
    return np.array(p.data.oMi[p._shoulders[hand]].translation)


def _closest_on_grid(p: StancePostures, hand: int, target: np.ndarray, n: int = 13) -> float:
    """The smallest hand-to-target distance (m) over a grid of n points per arm joint across
    its range (the brute-force answer the IK should match, within the grid's coarseness)."""
    q = p.q_nominal.copy()
    q[:3] = 0.0
    joints = p._arms[hand]
    axes = [np.linspace(p.desc.q_lower[j], p.desc.q_upper[j], n) for j in joints]
    best = np.inf
    fid = p._hand_ids[hand]
    for values in np.array(np.meshgrid(*axes, indexing="ij")).reshape(len(joints), -1).T:
        q[7 + joints] = values
        pin.framesForwardKinematics(p.model, p.data, q)
        best = min(best, float(np.linalg.norm(p.data.oMf[fid].translation - target)))
    return best


@pytest.mark.parametrize("beyond", [0.02, 0.05])
@pytest.mark.parametrize("hand", [0, 1])
def test_a_point_just_out_of_reach_reports_how_far(
    h1: StancePostures, hand: int, beyond: float
) -> None:
    """A point `beyond` past the longest reach, ahead and a little down from the shoulder:
    the residual is no more than the closest a grid search over the arm's joints gets (plus
    1 cm: the grid's 13 points per joint are 0.2-0.45 rad apart), where the full steps alone
    reported 0.2-0.8 m."""
    shoulder = _shoulder(h1, hand)
    direction = np.array([0.9, 0.0, -0.436])
    direction /= np.linalg.norm(direction)
    target = shoulder + (h1.max_reach[hand] + beyond) * direction
    _, residual, margin = h1.arms(HeldPose(0.98, (hand,), (tuple(target),)))
    assert residual[0] > REACH_TOL
    assert residual[0] <= _closest_on_grid(h1, hand, target) + 0.01
    assert margin == pytest.approx(-residual[0])


def test_reachable_points_are_reached(h1: StancePostures) -> None:
    """Within reach the first (full-step) solve converges and is what is kept."""
    for hand in (0, 1):
        target = _shoulder(h1, hand) + np.array([0.3, 0.0, -0.2])
        _, residual, margin = h1.arms(HeldPose(0.98, (hand,), (tuple(target),)))
        assert residual[0] < REACH_TOL and margin > 0.0


@pytest.mark.parametrize("robot", ["hector", "h1"])
def test_reach_shortfall_is_a_lower_bound_on_the_residual(robot: str) -> None:
    """`reach_shortfall` (which lets the refusal's search for a later pick skip the inverse
    kinematics, `payload.GRASP_REACH_BOUND_SLACK`) rests on `max_reach` being the arm's
    longest reach: no posture of 4000 drawn uniformly in the joints' working range reaches
    further than it plus a tenth of the slack; and for 40 hand points drawn 0-0.5 m beyond
    reach the residual `arms` reports is at least the bound less the slack."""
    from locoplan.plan.payload import GRASP_REACH_BOUND_SLACK

    p = StancePostures(load_robot_description(robot))
    rng = np.random.default_rng(11)
    q = p.q_nominal.copy()
    q[:3] = 0.0
    for hand in (0, 1):
        joints = p._arms[hand]
        shoulder = _shoulder(p, hand)
        longest = 0.0
        for _ in range(4000):
            q[7 + joints] = rng.uniform(p.q_lower[joints], p.q_upper[joints])
            pin.framesForwardKinematics(p.model, p.data, q)
            hand_point = p.data.oMf[p._hand_ids[hand]].translation
            longest = max(longest, float(np.linalg.norm(hand_point - shoulder)))
        assert longest <= p.max_reach[hand] + 0.1 * GRASP_REACH_BOUND_SLACK
        for _ in range(20):
            direction = rng.normal(size=3)
            direction[0] = abs(direction[0])  # ahead of the shoulder, as grips are
            direction /= np.linalg.norm(direction)
            target = shoulder + (p.max_reach[hand] + rng.uniform(0.0, 0.5)) * direction
            pose = HeldPose(0.9, (hand,), (tuple(target),))
            _, residual, _ = p.arms(pose)
            assert residual[0] >= p.reach_shortfall(pose) - GRASP_REACH_BOUND_SLACK
