"""Recovery steps (`locoplan.control.recovery`): the capture point, the step's foot, timing
and target against hand-worked cases, the schedule overlay the controller reads, and, closed
loop in MuJoCo, a standing robot that a push would tip over stepping instead."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from locoplan.control.recovery import (
    RecoverySchedule,
    RecoveryStep,
    capture_point,
    distance_outside,
    plan_recovery_step,
    support_hull,
)
from locoplan.scenario import load_scenario_file
from locoplan.sim.loop import Push
from locoplan.sim.run import RunOptions, run_scenario

TOE, HEEL = 0.09, 0.06  # HECTOR's sole ahead of / behind the foot's point (robot.yaml)
WIDTH = 0.1  # feet's points 0.1 m apart across
TAU = math.sqrt(0.54 / 9.81)  # HECTOR: CoM 0.54 m above the soles
FEET = np.array([[0.0, 0.05, 0.0], [0.0, -0.05, 0.0]])
YAWS = np.zeros(2)


def test_capture_point_and_distance_outside_the_soles() -> None:
    """xi = p + v sqrt(z / g) (exact); the hull of two parallel soles 0.1 m apart spans x in
    [-heel, toe], y in [-0.05, 0.05]: a point 0.03 m past the toe line is 0.03 m outside, one
    between the feet 0."""
    xi = capture_point(np.array([0.01, 0.0, 0.55]), np.array([0.4, -0.1, 0.2]), TAU)
    assert xi == pytest.approx([0.01 + 0.4 * TAU, -0.1 * TAU], abs=1e-15)
    hull = support_hull(FEET, YAWS, TOE, HEEL)
    assert distance_outside(np.array([TOE + 0.03, 0.0]), hull) == pytest.approx(0.03, abs=1e-12)
    assert distance_outside(np.array([0.0, 0.0]), hull) == 0.0
    assert distance_outside(np.array([-HEEL - 0.02, 0.09]), hull) == pytest.approx(
        math.hypot(0.02, 0.04), abs=1e-12
    )


def test_a_forward_capture_point_steps_the_foot_that_trails_sideways_to_where_xi_will_be() -> None:
    """xi 3 cm past the toes and 1 cm left of the middle: the right foot (farther from xi
    sideways) steps, the left holds the weight with its centre of pressure at its toe
    (0.09, 0.05); xi at touchdown is c + (xi - c) e^(T / tau), T = lead + swing, and the
    right foot's sole middle (its point + (toe - heel) / 2) lands there along x, the nominal
    width to the right of the left foot (xi_td is less far right than that)."""
    xi = np.array([TOE + 0.03, 0.01])
    lead, swing = 0.05, 0.16
    st = plan_recovery_step(2.0, xi, FEET, YAWS, 0.0, TOE, HEEL, WIDTH, 0.18, TAU, lead, swing)
    assert st.foot == 1
    assert (st.liftoff, st.touchdown) == pytest.approx((2.05, 2.21), abs=1e-12)
    cop = np.array([TOE, 0.05])
    xi_td = cop + (xi - cop) * math.exp((lead + swing) / TAU)
    assert xi_td[0] - 0.5 * (TOE - HEEL) < 0.18  # within reach: not clipped
    assert st.target[0] == pytest.approx(xi_td[0] - 0.5 * (TOE - HEEL), abs=1e-12)
    assert st.target[1] == pytest.approx(0.05 - WIDTH, abs=1e-12)
    assert st.target[2] == 0.0
    assert st.yaw == 0.0


def test_a_sideways_capture_point_steps_the_foot_on_its_side_outwards_within_reach() -> None:
    """xi 4 cm left of the left foot: the left foot steps out (never the right across it);
    xi_td from the right foot's nearest sole point (0, -0.05) lies 0.09 e^(T / tau) to its
    left, more than width + reach, so the step is clipped to width + reach across; along,
    the sole middle at xi_td's x (0 here, so its point 1.5 cm behind)."""
    xi = np.array([0.0, 0.09])
    st = plan_recovery_step(1.0, xi, FEET, YAWS, 0.0, TOE, HEEL, WIDTH, 0.18, TAU, 0.05, 0.16)
    assert st.foot == 0
    assert st.target[1] == pytest.approx(-0.05 + WIDTH + 0.18, abs=1e-12)
    assert st.target[0] == pytest.approx(-0.5 * (TOE - HEEL), abs=1e-12)
    # Turned 90 deg (trunk facing +y, its left is -x), the same case rotated.
    R = np.array([[0.0, -1.0], [1.0, 0.0]])
    feet = FEET.copy()
    feet[:, :2] = FEET[:, :2] @ R.T
    st90 = plan_recovery_step(
        1.0,
        R @ xi,
        feet,
        YAWS + math.pi / 2,
        math.pi / 2,
        TOE,
        HEEL,
        WIDTH,
        0.18,
        TAU,
        0.05,
        0.16,
    )
    assert st90.foot == 0
    assert st90.target[:2] == pytest.approx(R @ st.target[:2], abs=1e-12)


def test_the_schedule_takes_the_swing_out_of_the_stance_and_starts_a_stance_at_touchdown() -> None:
    sched = RecoverySchedule()
    step = RecoveryStep(1, 2.0, 2.2, np.array([0.1, -0.05, 0.0]), 0.0)
    sched.steps.append(step)
    times = np.array([1.9, 2.0, 2.1, 2.2, 2.5])
    planned = np.ones((5, 2), dtype=bool)
    flags = sched.flags(times, planned)
    assert flags[:, 0].all()
    assert flags[:, 1].tolist() == [True, False, False, True, True]
    # Planned: the initial stance (NaN) throughout, a later planned touchdown at 2.4.
    starts = sched.stance_starts(1, times, np.array([np.nan, np.nan, np.nan, np.nan, 2.4]))
    assert np.isnan(starts[0])
    assert starts[1:4].tolist() == [2.2, 2.2, 2.2]
    assert starts[4] == 2.4
    assert sched.swinging(1, 2.1) is step and sched.swinging(1, 2.2) is None
    assert sched.swinging(0, 2.1) is None
    assert sched.at_touchdown(1, 2.2) is step and sched.at_touchdown(0, 2.2) is None
    assert sched.busy(2.3, 0.16) and not sched.busy(2.37, 0.16)


def _stand_pushed(tmp_path: Path, force: tuple[float, float, float], recovery: bool) -> bool:
    path = tmp_path / "push.yaml"
    path.write_text(
        "version: 1\nname: push\ntasks:\n  - {action: stand, start: 0.0, duration: 4.0}\nend: 4.0\n"
    )
    loaded = load_scenario_file(path)
    options = RunOptions(
        out_dir=tmp_path, log=False, pushes=(Push(1.0, 0.1, force),), recovery_steps=recovery
    )
    result = run_scenario(loaded.scenario, loaded.text, options)
    return bool(result.metrics["fell"])


@pytest.mark.closed_loop
@pytest.mark.parametrize("force", [(60.0, 0.0, 0.0), (-60.0, 0.0, 0.0), (0.0, 60.0, 0.0)])
def test_a_push_that_tips_the_standing_robot_over_is_caught_by_a_step(
    tmp_path: Path, force: tuple[float, float, float]
) -> None:
    """6 N s on HECTOR's 17 kg standing (0.35 m/s: its capture point 8 cm out, past the soles
    forwards, backwards or sideways): without recovery steps the robot falls; with them it
    steps and stands (measured: every such push of 6 N s, and 8 N s forwards and sideways)."""
    assert _stand_pushed(tmp_path, force, recovery=False)
    assert not _stand_pushed(tmp_path, force, recovery=True)
