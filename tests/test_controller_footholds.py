"""The controller's footholds in turns: a foot whose stance the trunk turns over by more than
the hip yaw's room lands turned on towards the turn (no simulation: the plan and the
controller's foothold rule only)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from plan_fixtures import scenario_from_text

from locoplan.control.controller import (
    HIP_YAW_MARGIN,
    LocoManipulationController,
    wrap_angle,
)
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


def test_turning_footholds_keep_the_hip_yaw_within_its_room() -> None:
    """For every touchdown of a fast turn (87 deg/s average, the envelope's top), the foot
    lands turned on from the touchdown yaw by o = clip(d - R, 0, d / 2) towards the turn (d
    the reference's turn over the stance, R the hip yaw room: HECTOR's 30 deg less
    HIP_YAW_MARGIN), to 1e-9 rad; so the trunk's yaw relative to the foot over the stance (the
    hip yaw the leg holds) stays within max(R, d / 2), under 30 deg, where landing at the
    touchdown yaw would reach d, over 30 deg here. Slow stances (d <= R) land at the
    touchdown yaw."""
    plan = compile_plan(scenario_from_text(FAST_TURN))
    desc = load_robot_description("hector")
    ctl = LocoManipulationController(PinocchioRobot(desc), desc, plan)
    room = math.radians(30.0) - HIP_YAW_MARGIN
    assert ctl._hip_yaw_room == pytest.approx(room, abs=1e-9)
    p_c = np.array([0.0, 0.0, ctl.com_height])
    sweeps = []
    for k in range(2):
        for t_td, t_next in plan.stance_intervals(k):
            if not 0.5 < t_td < 2.5 or not math.isfinite(t_next):
                continue
            _, yaw = ctl._foothold(k, t_td - 0.05, t_td, p_c, np.zeros(3))
            at_td = plan.trunk.pose_at(t_td)[2]
            d = wrap_angle(plan.trunk.pose_at(t_next)[2] - at_td)
            o = min(max(abs(d) - room, 0.0), abs(d) / 2)
            assert wrap_angle(yaw - at_td) == pytest.approx(math.copysign(o, d), abs=1e-9)
            start = wrap_angle(at_td - yaw)
            end = wrap_angle(plan.trunk.pose_at(t_next)[2] - yaw)
            assert max(abs(start), abs(end)) <= max(room, abs(d) / 2) + 1e-9, (k, t_td)
            assert max(abs(start), abs(end)) < math.radians(30.0)
            sweeps.append(abs(d))
    # the turn is fast enough that landing at the touchdown yaw would leave the range, and
    # its first and last stances are slow enough to land at the touchdown yaw
    assert max(sweeps) > math.radians(30.0) and min(sweeps) < room
