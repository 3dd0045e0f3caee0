"""A drop that starts early in the turn towards its target hovers where the arms reach
(`locoplan.plan.payload.reachable_hovers`)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

import locoplan.plan.compiler as compiler
from locoplan.cli import app
from locoplan.plan import Plan, compile_plan
from locoplan.plan import constants as k
from locoplan.plan.payload import reachable_hovers
from locoplan.plan.statics import HeldPose, static_model
from locoplan.scenario import load_scenario
from locoplan.scenario.model import Scenario

DROP_EARLY_IN_TURN = Path(__file__).parent / "data" / "drop-early-in-turn.yaml"


def _hover(plan: Plan, scenario: Scenario) -> tuple[float, float]:
    """When (s) the hover of the plan's one drop ends and the arms' reach margin (m,
    negative: out of reach) of its pose then, in the trunk frame planned at that time."""
    (hold,) = plan.holds
    hands = ("L", "R")
    segments = [
        next(
            s
            for s in plan.manipulation.tracks[h].segments
            if s.task_index == hold.release_task and s.label == "hover"
        )
        for h in range(2)
    ]
    assert all(s.end.frame == "trunk" for s in segments) and hold.hands == hands
    pose = HeldPose(plan.trunk.height, (0, 1), tuple(s.end.point for s in segments))
    return segments[0].t1, static_model(scenario.robot).postures.arms(pose)[2]


def test_a_drop_early_in_its_turn_hovers_where_the_arms_reach(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """As written, the hover ends with the trunk 30 deg short of facing the platform and the
    place point across the body, 0.17 m beyond the left arm (0.043 m beyond it at the latest
    hover end that the drop's window allows, the trunk nearly facing the platform: a narrow
    box); the planned hover ends 0.3 s later, within HOVER_REACH_SLACK of that, and the
    lowering still ends inside the drop's window. The
    quasi-static plan, whose drop comes after the turn, keeps its hover."""
    scenario = load_scenario(DROP_EARLY_IN_TURN)
    plan = compile_plan(scenario)
    t, margin = _hover(plan, scenario)
    with monkeypatch.context() as m:
        m.setattr(compiler, "reachable_hovers", lambda plan, robot: {})
        t_written, margin_written = _hover(compile_plan(scenario), scenario)
    drop = plan.tasks[3]
    assert margin_written < -0.15
    assert t - t_written > 0.25
    # The bound: the margin at the latest hover end (-0.043 m) less the slack, to 2 mm (the
    # builder plans the hover's height and end afresh).
    assert margin >= -0.043 - k.HOVER_REACH_SLACK - 0.002
    assert reachable_hovers(plan, scenario.robot) == {}
    release = next(e.t for e in plan.events if e.kind == "release")
    assert t < release <= drop.end
    quasi = compile_plan(scenario, "quasi-static")
    assert reachable_hovers(quasi, scenario.robot) == {}
    quasi_drop = quasi.tasks[3]
    assert _hover(quasi, scenario)[0] <= quasi_drop.at_fraction(k.DROP_HOVER_END) + 1e-9


@pytest.mark.closed_loop
def test_a_drop_early_in_its_turn_places_the_parcel_in_mujoco(tmp_path: Path) -> None:
    """Closed loop (dynamic): the parcel ends on the platform, the robot standing (MuJoCo's
    state, as the run's metrics report it). Hovering as written, the parcel slipped in the
    right hand, came down on the platform 0.3 s before the lowering, was dragged round by
    the turn and fell to the floor."""
    metrics_path = tmp_path / "metrics.json"
    result = CliRunner().invoke(
        app,
        [
            "run",
            str(DROP_EARLY_IN_TURN),
            "--out",
            str(tmp_path / "runs"),
            "--metrics-json",
            str(metrics_path),
        ],
    )
    assert result.exit_code == 0, result.output
    metrics = json.loads(metrics_path.read_text())
    assert not metrics["fell"] and metrics["peak_torque_ratio"] <= 1.0
    assert metrics["objects"]["parcel"]["on"] == "platform"
    assert not metrics["objects"]["parcel"]["held"]
