"""compile_plan over every shipped scenario, events, export, evaluation cost (not timed)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from plan_fixtures import hector_scenario_files, repo_scenario, scenario_files

from locoplan.plan import PlanError, compile_plan
from locoplan.scenario import load_scenario
from locoplan.sim.robot_plan import compile_robot_plan

# Arm geometry of robots/hector (shared/robot.md): shoulders at (0, +-0.12, 0.17) in the
# trunk frame, reach 0.455 m from the shoulder.
SHOULDER_Y, SHOULDER_Z, ARM_REACH = 0.12, 0.17, 0.455


@pytest.mark.parametrize("path", scenario_files(), ids=lambda p: p.stem)
@pytest.mark.parametrize("strategy", ["dynamic", "quasi-static"])
def test_every_scenario_compiles_and_exports(path, strategy) -> None:
    scenario = load_scenario(path)
    plan = compile_robot_plan(scenario, strategy)
    assert plan.strategy == strategy
    assert plan.t_end >= max(t.end for t in plan.tasks)
    assert [e.t for e in plan.events] == sorted(e.t for e in plan.events)
    for task in plan.tasks:
        assert any(e.kind == "task_start" and e.task_index == task.index for e in plan.events)
    data = plan.to_dict()
    text = json.dumps(data, allow_nan=False)  # strict JSON: no inf/nan leaks out
    back = json.loads(text)
    assert back["scenario"] == scenario.name and back["strategy"] == strategy
    # The script's tasks, and a step the planner adds before a heavy standing lift (an index
    # past the script's, noted: `compiler._step_in_for_the_lift`).
    added = [t for t in back["tasks"] if t["index"] >= len(scenario.tasks)]
    assert len(back["tasks"]) == len(scenario.tasks) + len(added)
    assert all(t["action"] == "walk" for t in added)
    assert len(added) == sum("starts with a step" in n for n in plan.notes)
    assert back["summary"]["total_time"] == pytest.approx(plan.t_end)
    # every object that ends up placed is placed where the expectation says
    placed = scenario.expect.placed or {}
    for name, fixture in placed.items():
        assert plan.object_target(name).fixture == fixture


@pytest.mark.parametrize("path", hector_scenario_files(), ids=lambda p: p.stem)
def test_scenario_hand_targets_within_reach(path) -> None:
    plan = compile_plan(load_scenario(path))
    worst = 0.0
    for t in np.arange(0.0, plan.t_end, 0.01):
        st = plan.trunk_reference_at(float(t))
        ht = plan.hand_targets_at(float(t), st.position, st.yaw)
        c, s = math.cos(st.yaw), math.sin(st.yaw)
        for side, p in ((1.0, ht.p_L_world), (-1.0, ht.p_R_world)):
            shoulder = st.position + np.array(
                [-s * side * SHOULDER_Y, c * side * SHOULDER_Y, SHOULDER_Z]
            )
            worst = max(worst, float(np.linalg.norm(p - shoulder)))
    # 1 cm short of full stretch, so the elbow keeps some bend
    assert worst < ARM_REACH - 0.01


def test_unknown_strategy_and_task_past_end() -> None:
    scenario = repo_scenario("turn")
    with pytest.raises(PlanError, match="unknown strategy"):
        compile_plan(scenario, "fast")
    data = scenario.model_dump()
    data["end"] = 1.0
    bad = type(scenario).model_validate(data)
    with pytest.raises(PlanError, match="after the simulation end"):
        compile_plan(bad)


def test_evaluation_is_vectorised_and_cheap_enough() -> None:
    # Not a timing test (shared 2-core machine): checks the horizon-sized calls return the
    # right shapes; the measured costs are in the plan report (tens of microseconds).
    plan = compile_plan(repo_scenario("package-transfer"))
    times = 1.0 + 0.03 * np.arange(1, 21)
    assert plan.contact_flags(times).shape == (20, 2)
    ref = plan.trunk_reference(times)
    assert ref.position.shape == (20, 3) and ref.yaw.shape == (20,)
    assert plan.footholds_at(times).shape == (20, 2, 3)
    assert plan.object_reference(times).position.shape == (20, 3)
    assert plan.hand_contact_flags(times).shape == (20, 2)
