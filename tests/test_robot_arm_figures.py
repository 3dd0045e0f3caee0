"""The arms' planner figures (robot.yaml `planner`: hand_accel_limit, arm_moving_mass,
tuck_lift_duration) against the physics that sets them, recomputed from each robot's MJCF.

HECTOR's values are the constants checked on its envelope (locoplan.plan.constants); another
robot's scale from them (robots/h1/robot.yaml says how): the arms accelerating at a push the
trunk with m_arm a at the shoulders' height h above the soles, and the feet answer a pitch
moment of at most C = min(toe x weight, 2 x ANKLE_TORQUE_SHARE x the ankle's torque limit),
so a scales as C / (h m_arm); the moving mass scales with the arms' own mass; a tucked hand's
rise takes sqrt(size / acceleration) longer. The yaml states them to 2-3 digits: 1 %.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from locoplan.control.controller import ANKLE_TORQUE_SHARE
from locoplan.plan import constants as k
from locoplan.robot.description import RobotDescription, load_robot_description


def _arm_figures(desc: RobotDescription) -> tuple[float, float, float]:
    """(C / (h m_arm), which the arms' acceleration scales with (N m / (m kg)), m_arm (kg), trunk
    height (m)) at the nominal keyframe."""
    model = mujoco.MjModel.from_xml_path(str(desc.mjcf_path))
    data = mujoco.MjData(model)
    key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, desc.nominal_keyframe)
    mujoco.mj_resetDataKeyframe(model, data, key)
    mujoco.mj_forward(model, data)
    sole_z = np.mean(
        [
            data.site_xpos[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f)][2]
            for f in desc.foot_frames
        ]
    )

    def in_subtree(body: int, root: int) -> bool:
        while body != 0:
            if body == root:
                return True
            body = int(model.body_parentid[body])
        return False

    m_arm, heights = 0.0, []
    for chain in desc.arm_joint_indices:
        joint = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, desc.joint_names[chain[0]])
        root = int(model.jnt_bodyid[joint])
        m_arm += sum(float(model.body_mass[b]) for b in range(model.nbody) if in_subtree(b, root))
        heights.append(float(data.xanchor[joint][2] - sole_z))
    ankle = min(float(desc.torque_limits[leg[-1]]) for leg in desc.leg_joint_indices)
    moment = min(desc.foot_toe * desc.total_mass * 9.81, 2.0 * ANKLE_TORQUE_SHARE * ankle)
    return moment / (float(np.mean(heights)) * m_arm), m_arm, desc.base_height_nominal


def test_hector_arm_figures_are_the_constants() -> None:
    p = load_robot_description("hector").planner
    assert p.hand_accel_limit == k.HAND_ACCEL_LIMIT
    assert p.arm_moving_mass == k.ARM_MOVING_MASS
    assert p.tuck_lift_duration == k.TUCK_LIFT_DURATION


def test_h1_arm_figures_scale_from_hectors_by_its_description() -> None:
    scale_h, m_arm_h, size_h = _arm_figures(load_robot_description("hector"))
    desc = load_robot_description("h1")
    scale, m_arm, size = _arm_figures(desc)
    accel = k.HAND_ACCEL_LIMIT * scale / scale_h
    p = desc.planner
    assert p.hand_accel_limit == pytest.approx(accel, rel=0.01)
    assert p.arm_moving_mass == pytest.approx(k.ARM_MOVING_MASS * m_arm / m_arm_h, rel=0.01)
    lift = k.TUCK_LIFT_DURATION * math.sqrt((size / size_h) / (accel / k.HAND_ACCEL_LIMIT))
    assert p.tuck_lift_duration == pytest.approx(lift, rel=0.01)
    # H1's arms are slower than HECTOR's (its weak ankles and heavy, high arms), and heavier.
    assert p.hand_accel_limit < k.HAND_ACCEL_LIMIT
    assert p.arm_moving_mass > k.ARM_MOVING_MASS
