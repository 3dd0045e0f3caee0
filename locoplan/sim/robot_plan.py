"""The plan of a task script compiled for the robot the script names.

`locoplan.plan.compile_plan` takes the robot's figures as a `PlanGeometry` (default:
HECTOR's); every caller that plans for a run (`run`, `compare`, `plan`, `validate`) goes
through `compile_robot_plan`, which builds it from the robot's description
(`locoplan.plan.robot_geometry.plan_geometry`: robot.yaml `nominal.trunk_height`,
`stance_width`, `foot`, `contacts.hand_radius` and the `planner` section), so a script with
`robot: h1` is planned at H1's 0.98 m trunk height and 0.406 m stance, with its hands
starting where its keyframe holds them.
"""

from __future__ import annotations

from locoplan.exceptions import RobotDescriptionError
from locoplan.plan import Plan, PlanError, compile_plan
from locoplan.plan.robot_geometry import plan_geometry
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
    """`compile_plan(scenario, strategy)` with the robot's figures (`plan_geometry`); `desc`
    is the script's robot (loaded when not given). Raises what
    `compile_plan` raises, and `PlanError` located at `robot` for a robot whose description
    does not load (as the plan's payload checks do: `validate` passes such a script, `plan`
    and `run` refuse it with the loader's message)."""
    if desc is None:
        desc = plan_robot(scenario)
    return compile_plan(scenario, strategy, geometry=plan_geometry(desc))
