"""The controller's footholds in turns: a foot whose stance the trunk turns over by more than
the hip yaw's room lands turned on towards the turn (no simulation: the plan and the
controller's foothold rule only)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from plan_fixtures import scenario_from_text, stand_script

from locoplan.control.controller import (
    GRAVITY,
    HIP_YAW_MARGIN,
    POSITION_CONVERGENCE_TIME,
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

H1_STAND = stand_script("h1", 1.0)


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


def test_a_measured_velocity_error_moves_the_foothold_by_half_the_stance_plus_k() -> None:
    """The paper's foot placement p = p_c + v dt/2 + k (v - v_des) with the MEASURED CoM
    velocity v in the neutral-point term: a sideways velocity error of 0.2 m/s (the CoM
    falling towards the swing foot in an in-place turn) moves the foothold by (dt/2 + k) 0.2 m
    that way, dt the coming stance (half the gait period) and k the Raibert gain, to 1e-9 m.
    (With the reference's velocity in dt/2, as before, it moved by k 0.2 = 1 cm only, and
    seed 31415's in-place turns walked off sideways.) Nothing else moves it: the same plan
    point, the same yaw."""
    plan = compile_plan(scenario_from_text(FAST_TURN))
    desc = load_robot_description("hector")
    ctl = LocoManipulationController(PinocchioRobot(desc), desc, plan)
    p_c = np.array([0.0, 0.0, ctl.com_height])
    k, (t_td, _) = 0, plan.stance_intervals(0)[2]
    base, yaw0 = ctl._foothold(k, t_td - 0.05, t_td, p_c, np.zeros(3))
    moved, yaw1 = ctl._foothold(k, t_td - 0.05, t_td, p_c, np.array([0.0, 0.2, 0.0]))
    dt = plan.gait_period_at(t_td) / 2.0
    assert moved - base == pytest.approx(
        [0.0, (dt / 2.0 + ctl.s.raibert_gain) * 0.2, 0.0], abs=1e-9
    )
    assert yaw1 == yaw0


def test_a_position_error_moves_the_foothold_the_other_way_by_k_e_over_the_period() -> None:
    """The CoM's position error e (reference minus measured) is fed back as the velocity
    e / T_C wanted on top of the reference's: the foothold moves by -k e / T, T the gait
    period and k = 2 z / (g T_C) the linear inverted pendulum's gain for it (z the CoM's
    height above the soles, T_C = POSITION_CONVERGENCE_TIME; the CoM falls away from its
    foot, towards the reference), to 1e-9 m, on top of following the measured CoM by the
    same displacement. A CoM 0.1 m to the right of where the plan has it (without the error
    feedback nothing brought it back: seed 27449, locomotion-005) lands the foot 0.1 m +
    k 0.1 / T to the right: further from the reference, so that the CoM falls back towards
    it. k comes from the robot: HECTOR's is the 0.05 s measured on its envelopes (within
    1 %), H1's (a CoM 0.95 m above its soles) 1.75 times that."""
    plan = compile_plan(scenario_from_text(FAST_TURN))
    desc = load_robot_description("hector")
    ctl = LocoManipulationController(PinocchioRobot(desc), desc, plan)
    k, (t_td, _) = 0, plan.stance_intervals(0)[2]
    t = t_td - 0.05
    p_ref = ctl._com_reference(np.array([t]))[0][0]
    base, yaw0 = ctl._foothold(k, t, t_td, p_ref, np.zeros(3))
    off = np.array([0.0, -0.1, 0.0])
    moved, yaw1 = ctl._foothold(k, t, t_td, p_ref + off, np.zeros(3))
    period = plan.gait_period_at(t_td)
    expected = off[1] - ctl._position_gain * 0.1 / period  # e = +0.1: the foot goes by -k e / T
    assert moved - base == pytest.approx([0.0, expected, 0.0], abs=1e-9)
    assert yaw1 == yaw0
    z = ctl._capture_gain**2 * GRAVITY
    assert ctl._position_gain == pytest.approx(
        2.0 * z / (GRAVITY * POSITION_CONVERGENCE_TIME), rel=1e-12
    )
    assert ctl._position_gain == pytest.approx(0.05, rel=0.01)
    h1 = load_robot_description("h1")
    h1_ctl = LocoManipulationController(
        PinocchioRobot(h1), h1, compile_plan(scenario_from_text(H1_STAND))
    )
    assert h1_ctl._position_gain / ctl._position_gain == pytest.approx(1.75, abs=0.01)
