"""`compile_plan`: scenario -> Plan (contact schedule, trunk reference, hand targets, events)."""

from __future__ import annotations

import math
from dataclasses import replace

from locoplan.plan.clearance import fixture_obstacle
from locoplan.plan.errors import PlanError
from locoplan.plan.events import PlanEvent, sort_events
from locoplan.plan.footholds import build_footholds
from locoplan.plan.gait import FOOT_NAMES, build_contact_schedule
from locoplan.plan.manipulation import build_manipulation
from locoplan.plan.payload import (
    check_grasp_reach,
    check_payload,
    check_place_reach,
    with_lean_weights,
)
from locoplan.plan.plan import Plan
from locoplan.plan.tasks import plan_tasks, retime_quasi_static
from locoplan.plan.trunk import build_trunk_path
from locoplan.scenario.model import Scenario

STRATEGIES = ("dynamic", "quasi-static")
# Tolerance on "a task ends after the simulation end" (s): float noise of start + duration.
_END_TOLERANCE = 1e-9


def compile_plan(
    scenario: Scenario,
    strategy: str | None = None,
    *,
    base_height: float = 0.60,
    foot_width: float = 0.2,
) -> Plan:
    """Compile a validated scenario into a `Plan`.

    `strategy`: "dynamic" (tasks at the written times) or "quasi-static" (re-timed so that
    locomotion and manipulation never overlap); None takes the scenario's. `base_height`: trunk
    origin height of the reference (m); `foot_width`: lateral distance between the feet (m).
    Raises `PlanError` for a scenario the compiler cannot honour (overlapping locomotion, an
    object not held when dropped, an unknown object or fixture, a task ending after `end`),
    and for a carry or place pose the robot cannot hold statically (`locoplan.plan.payload`:
    `infeasible (payload)` / `infeasible (balance)`, located at the task).
    """
    strategy = scenario.strategy if strategy is None else strategy
    if strategy not in STRATEGIES:
        raise PlanError(f"unknown strategy '{strategy}'; allowed: {', '.join(STRATEGIES)}")
    if not (base_height > 0.0 and math.isfinite(base_height)):
        raise ValueError(f"base_height must be a positive length in m, got {base_height}")
    if not (foot_width > 0.0 and math.isfinite(foot_width)):
        raise ValueError(f"foot_width must be a positive length in m, got {foot_width}")

    tasks = plan_tasks(scenario)
    if strategy == "quasi-static":
        tasks = retime_quasi_static(tasks)
    end_shift = max(t.shift for t in tasks)
    t_end = scenario.end_time + end_shift
    for t in tasks:
        if t.end > t_end + _END_TOLERANCE:
            raise PlanError(
                f"{t.action} ends at {t.end:g} s, after the simulation end {t_end:g} s", t.index
            )

    contacts = build_contact_schedule(tasks, scenario.gait.period, scenario.gait.swing)
    start = scenario.robot_start
    trunk = build_trunk_path(
        tasks, start.position[0], start.position[1], math.radians(start.yaw), base_height
    )
    footholds = build_footholds(contacts, trunk, foot_width)
    swings = tuple(iv for f in range(2) for iv in contacts.swing_intervals(f))
    # Only a plan that holds something needs the robot's statics (the payload check loads
    # the same cached model): about 1 s in a fresh process, which locomotion need not pay.
    leg_torque = _leg_torque(scenario.robot) if scenario.objects else math.inf
    manipulation = build_manipulation(tasks, scenario, trunk, swings, leg_torque)

    # Drops and throws are done by the hands that picked the object.
    hand_words = {("L", "R"): "both", ("L",): "left", ("R",): "right"}
    hands_of_release = {
        h.release_task: hand_words[h.hands]
        for h in manipulation.holds
        if h.release_task is not None
    }
    tasks = tuple(
        replace(t, hands=hands_of_release[t.index]) if t.index in hands_of_release else t
        for t in tasks
    )

    events: list[PlanEvent] = []
    for t in tasks:
        events.append(PlanEvent(t.start, "task_start", t.index, t.action))
        events.append(PlanEvent(t.end, "task_end", t.index, t.action))
    for f, name in enumerate(FOOT_NAMES):
        for a, b, owner in zip(
            contacts.swing_start[f].tolist(),
            contacts.swing_end[f].tolist(),
            contacts.swing_task[f],
            strict=True,
        ):
            events.append(PlanEvent(a, "liftoff", owner, name))
            events.append(PlanEvent(b, "touchdown", owner, name))
    events.extend(manipulation.events)

    plan = Plan(
        scenario_name=scenario.name,
        strategy=strategy,
        tasks=tasks,
        t_end=t_end,
        end_shift=end_shift,
        base_height=base_height,
        foot_width=foot_width,
        gait_period=scenario.gait.period,
        gait_swing=scenario.gait.swing,
        contacts=contacts,
        footholds=footholds,
        trunk=trunk,
        manipulation=manipulation,
        events=sort_events(events),
        footprints=tuple(
            (o.center[0], o.center[1], o.yaw, o.half[0], o.half[1])
            for o in (fixture_obstacle(n, f) for n, f in scenario.fixtures.items())
        ),
    )
    check_grasp_reach(plan, scenario.robot)
    check_place_reach(plan, scenario.robot, scenario.fixtures)
    check_payload(plan, scenario.robot)
    return with_lean_weights(plan, scenario.robot)


def _leg_torque(robot: str) -> float:
    """The torque limit (N m) of the robot's weakest leg joint (its description); inf when
    the description cannot be read (the payload check then says why, for plans that hold
    something)."""
    from locoplan.exceptions import RobotDescriptionError
    from locoplan.plan.statics import static_model

    try:
        desc = static_model(robot).desc
    except RobotDescriptionError:
        return math.inf
    legs = [int(i) for side in desc.leg_joint_indices for i in side]
    return float(min(desc.torque_limits[legs]))
