"""locoplan.control.contact.foot_force_max: the per-foot normal-force bound of a robot."""

from __future__ import annotations

import pytest

from locoplan.control.contact import ContactLimits, foot_force_max
from locoplan.robot.description import load_robot_description


def test_hector_keeps_its_250_newtons_exactly() -> None:
    # HECTOR's link masses sum to 17 kg plus 4e-15 kg of decimal round-off; the bound must
    # still be the constant its runs were tuned with, to the last bit.
    mass = load_robot_description("hector").total_mass
    assert mass != 17.0 and abs(mass - 17.0) < 1e-12
    assert foot_force_max(mass) == 250.0 == ContactLimits().f_max


def test_the_bound_is_the_same_multiple_of_every_weight() -> None:
    # 250 N / (17 kg g) = 1.4991 weights per foot, for every robot (1 mN rounding).
    h1 = load_robot_description("h1")
    assert foot_force_max(h1.total_mass) == pytest.approx(250.0 * 51.437 / 17.0, abs=5e-4)
    assert foot_force_max(h1.total_mass) == 756.426
    for mass in (5.0, 17.0, 51.437, 80.0):
        assert foot_force_max(mass) / (mass * 9.81) == pytest.approx(
            250.0 / (17.0 * 9.81), abs=1e-5
        )


@pytest.mark.parametrize("mass", [0.0, -1.0, float("nan"), float("inf")])
def test_bad_masses_are_refused(mass: float) -> None:
    with pytest.raises(ValueError, match="positive number of kg"):
        foot_force_max(mass)
