"""The controller's footholds in turns: each foot lands yawed to the trunk reference's yaw at
the middle of its stance (no simulation: the plan and the controller's foothold rule only)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from plan_fixtures import scenario_from_text

from locoplan.control.controller import LocoManipulationController, wrap_angle
from locoplan.plan import compile_plan
from locoplan.robot.description import load_robot_description
from locoplan.robot.pinocchio_model import PinocchioRobot

FAST_TURN = """
version: 1
name: fast-turn
gait: {period: 0.46, swing: 0.22}
tasks:
  - {action: turn, angle: -178.6, start: 0.5, duration: 2.06}
end: 3.5
"""


def test_turning_footholds_take_the_mid_stance_yaw() -> None:
    """For every touchdown of a fast turn (87 deg/s average, the envelope's top), the foot's
    planned yaw is halfway between the reference yaws at its touchdown and at its next
    lift-off (to 1e-9 rad); so the trunk's yaw relative to the foot over the stance (the hip
    yaw the leg must hold) runs from -d/2 to +d/2 of its sweep d instead of 0 to d, within
    HECTOR's +-30 deg hip yaw where d itself (over 30 deg here) is not."""
    plan = compile_plan(scenario_from_text(FAST_TURN))
    desc = load_robot_description("hector")
    ctl = LocoManipulationController(PinocchioRobot(desc), desc, plan)
    p_c = np.array([0.0, 0.0, ctl.com_height])
    worst_sweep = 0.0
    for k in range(2):
        for t_td, t_next in plan.stance_intervals(k):
            if not 0.5 < t_td < 2.5 or not math.isfinite(t_next):
                continue
            _, yaw = ctl._foothold(k, t_td - 0.05, t_td, p_c, np.zeros(3))
            start = wrap_angle(plan.trunk.pose_at(t_td)[2] - yaw)
            end = wrap_angle(plan.trunk.pose_at(t_next)[2] - yaw)
            assert start == pytest.approx(-end, abs=1e-9), (k, t_td)
            sweep = abs(end - start)
            worst_sweep = max(worst_sweep, sweep)
            assert abs(start) < math.radians(30.0)
    # the turn is fast enough that landing at the touchdown yaw would leave the range
    assert worst_sweep > math.radians(30.0)
