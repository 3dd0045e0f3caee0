"""locoplan.sim.robot_plan.compile_robot_plan: the plan at the script's robot's geometry."""

from __future__ import annotations

from pathlib import Path

import pytest
from plan_fixtures import repo_scenario, scenario_from_text

from locoplan.plan import PlanError, compile_plan
from locoplan.robot.description import load_robot_description
from locoplan.scenario.model import Scenario
from locoplan.sim.robot_plan import compile_robot_plan

H1_STAND = """
version: 1
name: h1-stand
robot: h1
tasks:
  - {action: stand, start: 0.0, duration: 2.0}
"""


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
