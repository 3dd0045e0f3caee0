"""The controller's held-load model around a drop's release (no simulation: the plan and the
controller's load bookkeeping only)."""

from __future__ import annotations

import numpy as np
import pytest
from plan_fixtures import scenario_from_text

from locoplan.control.controller import (
    FOOT_FIXTURE_CLEARANCE,
    LOAD_LEAD,
    LocoManipulationController,
)
from locoplan.plan import compile_plan
from locoplan.robot.description import load_robot_description
from locoplan.robot.pinocchio_model import PinocchioRobot

HOLD_AND_PUT_BACK = """
version: 1
name: hold-and-put-back
objects:
  block: {shape: box, size: [0.2, 0.2, 0.15], mass: 5.0, position: [0.33, 0.0, 0.535]}
fixtures:
  table: {kind: table, position: [0.48, 0.0, 0.0], size: [0.4, 0.6, 0.46]}
tasks:
  - {action: stand, start: 0.0, duration: 0.5}
  - {action: pick, object: block, start: 0.5, duration: 1.5}
  - {action: stand, start: 2.0, duration: 2.0}
  - {action: drop, object: block, onto: table, start: 4.0, duration: 1.2}
end: 6.0
"""


def test_com_shift_keeps_leaning_back_while_the_hands_hold_the_load() -> None:
    """While the wrist sensors measure the whole weight in the hands, the CoM shift must point
    away from the object for whatever load it counts, up to the planned release: the lead
    time (t + LOAD_LEAD) of the last instants before it lies past the release, where the plan
    has no object between the hands, and the shift there once fell to zero with the measured
    load still on (the CoM reference jumped 7 cm forward; envelope seed 11, transfer-008 fell
    onto its target). Its size is the share `_lean_share` (the plan's lean weight for this
    5 kg hold) of m_o d / (m + m_o) for the load counted (`shift_mass`) and the object's
    planned offset d from the CoM reference, checked to 1 mm (the object path's cache rounds
    times to 1 us)."""
    plan = compile_plan(scenario_from_text(HOLD_AND_PUT_BACK))
    desc = load_robot_description("hector")
    ctl = LocoManipulationController(PinocchioRobot(desc), desc, plan)
    (hold,) = plan.holds
    weight = hold.mass * 9.81
    for t in np.linspace(hold.release - 2.0 * LOAD_LEAD, hold.release - 1e-3, 13):
        ctl._update_load(float(t), weight)
        lead = np.array([t + LOAD_LEAD])
        mass = ctl.shift_mass(lead)
        p_com, *_ = ctl._com_reference(lead)
        shift = ctl._com_shift(lead, mass, p_com)[0]
        obj = plan.object_positions(np.array([min(lead[0], hold.release - 1e-3)]))[0]
        d = obj[:2] - p_com[0, :2]
        full = mass[0] / (ctl.mass + mass[0]) * d
        share = ctl._lean_share(np.array([np.linalg.norm(full)]), np.array([hold.lean_weight]))
        expected = -share[0] * full
        # Forward is +x (robot_start yaw 0): backwards wherever load is counted.
        assert mass[0] > 0.05 * hold.mass, t
        assert shift[0] < -0.05 * mass[0] / (ctl.mass + mass[0]), (t, shift)
        np.testing.assert_allclose(shift, expected, atol=1e-3)


TURN_BETWEEN_FIXTURES = """
version: 1
name: turn-between-fixtures
fixtures:
  table: {kind: table, position: [0.0, 0.30, 0.0], size: [0.4, 0.3, 0.45]}
tasks:
  - {action: turn, angle: 90, start: 0.0, duration: 1.5}
end: 2.0
"""


def test_footholds_keep_off_fixture_footprints() -> None:
    """A foothold whose toe, sole site or heel would stand within FOOT_FIXTURE_CLEARANCE of a
    fixture's footprint is moved out across the nearest side, by just enough (to 1 um); one
    clear of it stays where it was."""
    plan = compile_plan(scenario_from_text(TURN_BETWEEN_FIXTURES))
    desc = load_robot_description("hector")
    ctl = LocoManipulationController(PinocchioRobot(desc), desc, plan)
    # The table's near side is at y = 0.15; a foot yawed 90 deg points its toe at it.
    near = 0.30 - 0.15
    p = np.array([0.0, 0.10, 0.0])
    ctl._off_footprints(p, np.pi / 2)
    assert p[0] == pytest.approx(0.0, abs=1e-12)
    assert p[1] + desc.foot_toe == pytest.approx(near - FOOT_FIXTURE_CLEARANCE, abs=1e-6)
    clear = np.array([0.0, -0.10, 0.0])
    ctl._off_footprints(clear, np.pi / 2)
    np.testing.assert_array_equal(clear, [0.0, -0.10, 0.0])
    # Yawed 0 the foot lies along the side: only its width counts.
    side = np.array([0.05, 0.14, 0.0])
    ctl._off_footprints(side, 0.0)
    assert side[1] == pytest.approx(near - FOOT_FIXTURE_CLEARANCE, abs=1e-6)


def test_lean_share_leaves_equal_centre_of_pressure_margins_loaded_and_unloaded() -> None:
    """With lean weight 0, `_lean_share` (beta) splits the load shift s so that the loaded
    combined CoM has as much room to the toes as the unloaded robot's CoM has to the heels:
    t - (c - beta s + s) = (c - beta s) + h, with c the nominal CoM ahead of the sole site (the
    pinocchio model at the nominal pose), checked to 1e-9 m for loads whose shift stays below
    the support; weight w adds w of the rest (1 - beta), so w = 1 is the whole shift."""
    plan = compile_plan(scenario_from_text(HOLD_AND_PUT_BACK))
    desc = load_robot_description("hector")
    ctl = LocoManipulationController(PinocchioRobot(desc), desc, plan)
    c = ctl.com_offset[0] - np.mean(ctl.foot_offsets[:, 0])
    toe, heel = desc.foot_toe, desc.foot_heel
    sizes = np.array([0.02, 0.05, 0.08, 0.11])
    beta = ctl._lean_share(sizes, np.zeros(4))
    robot = c - beta * sizes
    np.testing.assert_allclose(toe - (robot + sizes), robot + heel, atol=1e-9)
    # HECTOR's nominal CoM sits over the middle of its support: half the shift for any load.
    np.testing.assert_allclose(beta, 0.5, atol=0.02)
    np.testing.assert_allclose(ctl._lean_share(sizes, np.ones(4)), 1.0, atol=1e-12)
    half = ctl._lean_share(sizes, np.full(4, 0.5))
    np.testing.assert_allclose(half, beta + 0.5 * (1.0 - beta), atol=1e-12)


def test_lean_weights_follow_the_holds_shift_window() -> None:
    """`_lean_weights` gives a hold's plan weight from its grasp to LOAD_RAMP_DOWN after its
    release (the window the CoM shift counts its load in) and 1 elsewhere."""
    plan = compile_plan(scenario_from_text(HOLD_AND_PUT_BACK))
    desc = load_robot_description("hector")
    ctl = LocoManipulationController(PinocchioRobot(desc), desc, plan)
    (hold,) = plan.holds
    t = np.array([hold.grasp - 0.01, hold.grasp + 0.01, hold.release - 0.01, 99.0])
    np.testing.assert_array_equal(
        ctl._lean_weights(t), [1.0, hold.lean_weight, hold.lean_weight, 1.0]
    )
