"""The plan of a task script compiled for the robot the script names.

`locoplan.plan.compile_plan` takes the trunk height of its reference and the lateral spacing
of its footholds as arguments (defaults: HECTOR's 0.60 m and 0.2 m); every caller that plans
for a run (`run`, `compare`, `plan`, `validate`) goes through `compile_robot_plan`, which
takes them from the robot's description (robot.yaml `nominal.trunk_height` and
`stance_width`), so a script with `robot: h1` is planned at H1's 0.98 m and 0.406 m.
"""

from __future__ import annotations

from locoplan.exceptions import RobotDescriptionError
from locoplan.plan import Plan, PlanError, compile_plan
from locoplan.robot.description import RobotDescription, load_robot_description
from locoplan.scenario import Scenario


def plan_robot(scenario: Scenario) -> RobotDescription:
    """The description of the script's robot; `PlanError` located at `robot` when it does not
    load (what `compile_robot_plan` raises then)."""
    try:
        return load_robot_description(scenario.robot)
    except RobotDescriptionError as exc:
        raise PlanError(f"cannot plan for the robot: {exc}", loc=("robot",)) from exc


def compile_robot_plan(
    scenario: Scenario, strategy: str | None = None, desc: RobotDescription | None = None
) -> Plan:
    """`compile_plan(scenario, strategy)` at the robot's nominal trunk height and foothold
    spacing; `desc` is the script's robot (loaded when not given). Raises what
    `compile_plan` raises, and `PlanError` located at `robot` for a robot whose description
    does not load (as the plan's payload checks do: `validate` passes such a script, `plan`
    and `run` refuse it with the loader's message)."""
    if desc is None:
        desc = plan_robot(scenario)
    return compile_plan(
        scenario, strategy, base_height=desc.base_height_nominal, foot_width=desc.stance_width
    )
