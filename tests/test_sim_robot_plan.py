"""locoplan.sim.robot_plan.compile_robot_plan: the plan at the script's robot's geometry."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from plan_fixtures import repo_scenario, scenario_from_text, stand_script

from locoplan.plan import PlanError, compile_plan
from locoplan.plan import constants as k
from locoplan.plan.robot_geometry import HECTOR_GEOMETRY, plan_geometry
from locoplan.robot.description import load_robot_description
from locoplan.robot.pinocchio_model import PinocchioRobot
from locoplan.scenario.model import Scenario
from locoplan.sim.robot_plan import compile_robot_plan

H1_STAND = stand_script("h1", 2.0)


def test_hector_plans_as_compile_plan_defaults() -> None:
    scenario = repo_scenario("package-transfer")
    plan = compile_robot_plan(scenario)
    default = compile_plan(scenario)
    assert (plan.base_height, plan.foot_width) == (default.base_height, default.foot_width)
    assert (plan.base_height, plan.foot_width) == (0.60, 0.2)
    assert plan.to_dict() == default.to_dict()


def test_h1_plans_at_its_own_height_and_stance() -> None:
    desc = load_robot_description("h1")
    plan = compile_robot_plan(scenario_from_text(H1_STAND))
    assert plan.base_height == desc.base_height_nominal == 0.98
    assert plan.foot_width == desc.stance_width == 0.40572
    # The standing trunk reference is at H1's height, the feet under its hips.
    assert abs(plan.trunk_reference_at(1.0).position[2] - 0.98) < 1e-12


def test_a_robot_that_does_not_load_is_a_plan_error_at_robot(tmp_path: Path) -> None:
    # As the payload checks do (`validate` lets the script pass, `plan` and `run` refuse it at
    # its `robot:` line): an MJCF path is a valid robot file to the format, not to the loader.
    bad = Scenario.model_validate(
        {
            "version": 1,
            "name": "xml",
            "robot": str(tmp_path / "mine.xml"),
            "tasks": [{"action": "stand", "start": 0.0, "duration": 1.0}],
        }
    )
    with pytest.raises(PlanError, match=r"cannot plan for the robot: .*no robot description") as e:
        compile_robot_plan(bad)
    assert e.value.loc == ("robot",)


def test_hector_geometry_is_the_plan_constants() -> None:
    # HECTOR's robot.yaml has no `planner` section: every figure the plan reads comes from the
    # loader's defaults and must be the constants' values exactly (plans stay bit-identical).
    assert plan_geometry(load_robot_description("hector")) == HECTOR_GEOMETRY
    assert HECTOR_GEOMETRY.hand_default_in_trunk == k.HAND_DEFAULT_IN_TRUNK
    assert HECTOR_GEOMETRY.grasp_tolerance == k.GRASP_TOLERANCE
    assert HECTOR_GEOMETRY.grasp_clearance == k.GRASP_CLEARANCE
    assert HECTOR_GEOMETRY.footprint_radius == k.ROBOT_FOOTPRINT_RADIUS


def _h1_hand_in_pelvis(**angles_deg: float) -> np.ndarray:
    """H1's left hand site relative to the pelvis origin at the nominal pose, with some joints
    moved (pinocchio forward kinematics)."""
    desc = load_robot_description("h1")
    robot = PinocchioRobot(desc)
    q = robot.nominal_q().copy()
    q[:3] = 0.0
    for name, deg in angles_deg.items():
        q[7 + desc.joint_names.index(name)] = np.radians(deg)
    robot.update(q, np.zeros(robot.nv))
    return robot.frame_position(desc.hand_frames[0])


def test_h1_planner_figures_are_its_models() -> None:
    """robot.yaml's `planner` section for H1 against the model it was derived from: the default
    hands where the keyframe puts them (so a standing H1 starts with its arms at rest), the
    tuck at the keyframe's arm with the elbow at +60 deg (1e-5 m: the file's 6 digits), the
    hip yaw range the joints' own, the stride the leg's kinematic reach (within 1 cm)."""
    desc = load_robot_description("h1")
    geo = plan_geometry(desc)
    assert geo.hand_default_in_trunk == pytest.approx(_h1_hand_in_pelvis(), abs=1e-5)
    assert geo.hand_tuck_in_trunk == pytest.approx(_h1_hand_in_pelvis(L_elbow=60.0), abs=1e-5)
    yaw = desc.leg_joint_indices[0][0]
    assert desc.joint_names[yaw] == "L_hip_yaw"
    assert geo.hip_yaw_range == pytest.approx(desc.q_upper[yaw], abs=1e-8)
    robot = PinocchioRobot(desc)
    q = robot.nominal_q().copy()
    robot.update(q, np.zeros(robot.nv))
    hip, knee, ankle = (
        robot.data.oMi[robot.model.getJointId(n)].translation
        for n in ("L_hip_pitch", "L_knee", "L_ankle")
    )
    leg = np.linalg.norm(knee - hip) + np.linalg.norm(ankle - knee)
    stride = np.sqrt(leg**2 - (hip[2] - ankle[2]) ** 2)
    assert stride - 0.01 <= geo.walk_stride <= stride
    # The hand sphere closes 1 cm beyond touching and keeps 3 cm before the grasp, as HECTOR's.
    assert geo.grasp_tolerance == pytest.approx(desc.hand_radius + 0.01, abs=1e-12)
    assert geo.grasp_clearance == pytest.approx(desc.hand_radius + 0.03, abs=1e-12)


def test_h1_hands_start_where_its_keyframe_holds_them() -> None:
    desc = load_robot_description("h1")
    plan = compile_robot_plan(scenario_from_text(H1_STAND))
    assert plan.geometry == plan_geometry(desc)
    for hand, side in ((0, 1.0), (1, -1.0)):
        x, y, z = desc.planner.hand_default
        assert plan.manipulation.tracks[hand].initial.point == (x, side * y, z)
