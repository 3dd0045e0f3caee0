"""locoplan.sim.run.controller_settings: the contact limits come from the script's robot."""

from __future__ import annotations

from plan_fixtures import repo_scenario, scenario_from_text, stand_script

from locoplan.control.controller import ControllerSettings
from locoplan.robot.description import load_robot_description
from locoplan.sim.run import RunOptions, controller_settings

H1_STAND = stand_script("h1", 1.0)


def test_hector_settings_are_the_former_constants() -> None:
    s = controller_settings(repo_scenario("stand"), RunOptions())
    default = ControllerSettings()
    # HECTOR's robot.yaml foot (0.09 / 0.06 m) and 250 N: what the defaults always held.
    assert s.limits == default.limits
    assert (s.mpc.toe, s.mpc.heel, s.mpc.f_max, s.mpc.f_min) == (0.09, 0.06, 250.0, 10.0)
    assert s.mpc.mu_torsion == default.mpc.mu_torsion


def test_h1_settings_use_its_feet_and_weight() -> None:
    desc = load_robot_description("h1")
    s = controller_settings(scenario_from_text(H1_STAND), RunOptions(f_min=5.0), desc)
    assert (s.limits.toe, s.limits.heel) == (s.mpc.toe, s.mpc.heel) == (0.14, 0.035)
    assert s.limits.f_max == s.mpc.f_max == 756.426
    assert s.limits.f_min == s.mpc.f_min == 5.0
