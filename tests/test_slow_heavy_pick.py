"""A heavy object held standing is picked no faster than HEAVY_PICK_MIN (the paper's 2 s).

HECTOR envelope seed 79021, standing-hold-025: 13.64 kg gripped 0.30 m out, written as a
0.86 s pick. At the phase fractions the hands took the block's weight within 0.13 s; the
lean could not follow, the robot rocked onto its toes and the block went back onto its table
(it rose 2 cm at most: not held). Picked over 2 s, it is held 6-7 cm up until it is put back.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from plan_fixtures import hold_script, scenario_from_text

from locoplan.log.reader import read_log
from locoplan.plan import compile_plan
from locoplan.plan.compiler import HEAVY_PICK_MIN
from locoplan.scenario import load_scenario_file
from locoplan.sim.run import RunOptions, run_scenario

DATA = Path(__file__).parent / "data" / "hector-heavy-short-pick.yaml"


def _short(mass: float, drop_at: float = 5.5) -> str:
    """hold_script's geometry with a 1.0 s pick (0.5-1.5 s) and the drop at `drop_at`."""
    text = hold_script(mass)
    text = text.replace("start: 0.5, duration: 2.0}", "start: 0.5, duration: 1.0}")
    text = text.replace(
        "{action: stand, start: 2.5, duration: 3.0}", "{action: stand, start: 1.5, duration: 4.0}"
    )
    return text.replace("start: 5.5, duration: 1.5}", f"start: {drop_at}, duration: 1.5}}")


def test_a_short_heavy_standing_pick_lasts_the_minimum_with_a_note() -> None:
    # The planner steps nearer first (`compiler._step_in_off_the_tolerance`); the pick then
    # starts after the step and lasts the minimum, not its written 1.0 s.
    plan = compile_plan(scenario_from_text(_short(7.0)))
    pick = next(t for t in plan.tasks if t.action == "pick")
    walk = next(t for t in plan.tasks if t.action == "walk")
    assert walk.start == 0.5 and pick.start == pytest.approx(walk.end)
    assert pick.end == pytest.approx(pick.start + HEAVY_PICK_MIN)
    # The note quotes the pick as the script writes it (0.50-1.50 s), not as stepped.
    assert any(
        n.startswith("the pick of 'block' (7 kg, ")
        and f"written from 0.50 s to 1.50 s ends at {pick.end:.2f} s so that its weight "
        "comes on slowly"
        in n
        for n in plan.notes
    ), plan.notes
    # The time it was given is for the weight to come on slowly: the controller feeds the
    # hands no more of it than the load ramp has come to (`ObjectHold.slow_lift`).
    (hold,) = plan.holds
    assert hold.slow_lift


def test_a_heavy_pick_followed_by_a_turn_is_not_slow_lifted() -> None:
    """Where the robot steps while holding, the lean is in place before the lift-off and the
    weight comes on at once (`_lift_mass`'s first case): no slow lift for 8 kg (heavy: see
    the stand's case above)."""
    text = hold_script(8.0).replace(
        "{action: stand, start: 2.5, duration: 3.0}",
        "{action: turn, angle: 20, start: 2.5, duration: 1.5}\n"
        "  - {action: turn, angle: -20, start: 4.0, duration: 1.5}",
    )
    assert "action: turn" in text
    (hold,) = compile_plan(scenario_from_text(text)).holds
    assert not hold.slow_lift


@pytest.mark.parametrize(
    ("mass", "drop_at", "why"),
    [
        (1.0, 5.5, "light: its weight's moment is under half the hip pitch's limit"),
        (7.0, 2.0, "the drop starts before the longer pick would end"),
    ],
)
def test_a_pick_is_left_as_written(mass: float, drop_at: float, why: str) -> None:
    plan = compile_plan(scenario_from_text(_short(mass, drop_at)))
    assert plan.tasks[1].end == pytest.approx(1.5), why
    assert not any(n.startswith("the pick of") for n in plan.notes)
    # Light, or picked in 1 s: the weight comes on as the hands take it.
    assert not any(h.slow_lift for h in plan.holds)


@pytest.mark.closed_loop
def test_a_heavy_block_picked_slowly_is_held(tmp_path: Path) -> None:
    loaded = load_scenario_file(DATA)
    result = run_scenario(loaded.scenario, loaded.text, RunOptions(out_dir=tmp_path))
    m = result.metrics
    assert not m["fell"] and m["passed"], m["expectations"]
    assert m["peak_torque_ratio"] <= 1.0
    assert m["objects"]["block"]["on"] == "table"
    assert "pick.block" not in m["expectations"]  # held from the pick's end to the drop
    assert m["task_goal_times"][1] is not None
    # The plan's pick ends at 2.5 s (3.3 s since the planner steps nearer first: the paper's
    # 2 s after the step's 0.8 s); the block rests at 0.577 m: held at least 4 cm up from
    # then until the drop starts at 4.85 s (measured 6.7-7.0 cm before the step; before the
    # slow pick: at most 2 cm, and back on the table).
    pick_end = next(t.end for t in result.plan.tasks if t.action == "pick")
    assert pick_end <= 3.3 + 1e-9
    assert result.log_path is not None
    heights = [
        (t, e.cubes[0].pose.position.z)
        for t, msg in read_log(result.log_path).messages("/scene/objects")
        for e in msg.entities
        if e.id.startswith("object/block") and e.cubes
    ]
    held = np.array([z for t, z in heights if pick_end <= t <= 4.85])
    assert held.size and held.min() >= 0.577 + 0.04, held.min()
