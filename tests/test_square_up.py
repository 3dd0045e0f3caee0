"""Square-up steps (`locoplan.control.recovery.plan_square_up_step`): which foot steps back to
its nominal place and when it does not, against hand-worked cases, and, closed loop in MuJoCo,
H1 shuffling its right foot back after a walk that left it 19 cm off, then turning 171 deg
(tests/data/h1-walk-off-then-turn.yaml; without added steps it falls in that turn)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from locoplan.control.recovery import plan_square_up_step
from locoplan.log.reader import read_log
from locoplan.scenario import load_scenario_file
from locoplan.sim.run import RunOptions, run_scenario

WIDTH = 0.4  # nominal places 0.4 m apart across
EXCESS = 0.1  # m beyond width / 2 from the places' centre before a foot steps
NOMINAL = np.array([[0.0, 0.2, 0.0], [0.0, -0.2, 0.0]])


def _rotated(p: np.ndarray, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    out = p.copy()
    out[:, 0] = c * p[:, 0] - s * p[:, 1]
    out[:, 1] = s * p[:, 0] + c * p[:, 1]
    return out


def test_feet_at_or_near_their_places_take_no_step() -> None:
    """At the places: none. The right foot 0.1 m behind its place is sqrt(0.2^2 + 0.1^2) =
    0.224 m from the centre, 0.024 m beyond width / 2: within the 0.1 m excess, none."""
    assert plan_square_up_step(1.0, NOMINAL, NOMINAL, 0.0, WIDTH, EXCESS, 0.2, 0.2) is None
    feet = NOMINAL + np.array([[0.0, 0.0, 0.0], [-0.1, 0.0, 0.0]])
    assert plan_square_up_step(1.0, feet, NOMINAL, 0.0, WIDTH, EXCESS, 0.2, 0.2) is None


@pytest.mark.parametrize("yaw_deg", [0.0, 90.0, -131.0])
def test_the_foot_farthest_beyond_half_the_width_steps_to_its_place(yaw_deg: float) -> None:
    """The right foot 0.19 m behind and 0.1 m outside its place (0.355 m from the centre,
    0.155 m beyond width / 2), the left one 0.05 m behind (0.006 m beyond): the right steps,
    lifting `lead` after t, landing one swing later at its place with the trunk's yaw; the
    same with the scene turned about the vertical."""
    yaw = math.radians(yaw_deg)
    feet = NOMINAL + np.array([[-0.05, 0.0, 0.0], [-0.19, -0.1, 0.0]])
    st = plan_square_up_step(
        2.0, _rotated(feet, yaw), _rotated(NOMINAL, yaw), yaw, WIDTH, EXCESS, 0.2, 0.22
    )
    assert st is not None
    assert st.foot == 1 and st.reason == "square-up"
    assert (st.liftoff, st.touchdown) == pytest.approx((2.2, 2.42), abs=1e-12)
    assert st.target == pytest.approx(_rotated(NOMINAL, yaw)[1], abs=1e-12)
    assert st.yaw == yaw


def test_no_step_where_the_place_is_too_near_the_other_foot() -> None:
    """The right foot far behind (0.3 m), the left slid 0.25 m to the right (0.05 m left of
    the centre line): the right's place would be 0.15 m across from it, under width / 2 =
    0.2 m (the feet would meet), so no step; with the left foot 0.2 m across, the step."""
    feet = np.array([[0.0, -0.05, 0.0], [-0.3, -0.2, 0.0]])
    assert plan_square_up_step(1.0, feet, NOMINAL, 0.0, WIDTH, EXCESS, 0.2, 0.2) is None
    feet[0, 1] = 0.0
    st = plan_square_up_step(1.0, feet, NOMINAL, 0.0, WIDTH, EXCESS, 0.2, 0.2)
    assert st is not None and st.foot == 1


DATA = Path(__file__).parent / "data" / "h1-walk-off-then-turn.yaml"


def _run(tmp_path: Path, steps: bool) -> tuple[dict[str, object], list[dict[str, object]]]:
    loaded = load_scenario_file(DATA)
    out = tmp_path / ("with" if steps else "without")
    options = RunOptions(out_dir=out, recovery_steps=steps)
    result = run_scenario(loaded.scenario, loaded.text, options)
    assert result.log_path is not None
    events = [m for _, m in read_log(result.log_path).messages("/events")]
    added = [e for e in events if e["kind"] == "step_added"]
    return result.metrics, added


@pytest.mark.closed_loop
def test_h1_squares_up_its_right_foot_before_the_turn_after_a_walk_that_left_it_off(
    tmp_path: Path,
) -> None:
    """The walk's last (capture-point) step puts H1's right foot 19 cm off its plan, the
    standing reference 10 cm from the left foot and 34 cm from the right. Without added steps
    the turn's first lift-off takes the loaded left foot and the robot falls (measured at
    5.9 s); with them, the right foot steps back to its place in the 0.8 s stand, the turn
    is done (final yaw within 10 deg of the plan's, no fall) within H1's torque limits."""
    metrics, added = _run(tmp_path, steps=False)
    assert metrics["fell"]
    metrics, added = _run(tmp_path, steps=True)
    assert not metrics["fell"]
    square = [e for e in added if e["reason"] == "square-up"]
    assert square and square[0]["detail"] == "R"
    assert 2.43 < float(square[0]["liftoff"]) < 3.26  # between the walk's end and the turn
    final = metrics["final_base"]
    planned_yaw = -48.2 + 171.4
    assert abs(final["yaw_deg"] - planned_yaw) < 10.0
    assert metrics["peak_torque_ratio"] <= 1.0
