"""H1 picks, holds and puts back a box standing (scenarios/h1-standing-hold.yaml) under
locoplan's controller in MuJoCo, asserted from the simulation state: the plan's hand poses,
grasp clearances and tolerance are H1's (robot.yaml `planner`, `contacts.hand_radius`), not
HECTOR's. About 10 s of wall time (8 s simulated)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from locoplan.robot.description import load_robot_description
from locoplan.scenario import load_scenario_file
from locoplan.sim.run import RunOptions, run_scenario

pytestmark = pytest.mark.closed_loop

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "h1-standing-hold.yaml"


def test_h1_picks_holds_and_puts_back_a_box(tmp_path: Path) -> None:
    desc = load_robot_description("h1")
    loaded = load_scenario_file(SCENARIO)
    scenario = loaded.scenario
    box, table = scenario.objects["box"], scenario.fixtures["table"]
    result = run_scenario(scenario, loaded.text, RunOptions(out_dir=tmp_path))
    rec = result.record
    t = np.asarray(rec.t)
    pos = np.asarray(rec.base_position)  # the pelvis (MuJoCo's free joint), every 10 ms
    p_box = np.asarray(rec.object_positions["box"])
    assert rec.sim_time >= scenario.end_time - 1e-6
    # Did not fall: the pelvis stays within 3 cm of its nominal 0.98 m (measured 0.5 cm), far
    # above the fall height (0.55 m), and upright within 3 deg.
    assert not result.metrics["fell"]
    assert np.max(np.abs(pos[:, 2] - desc.base_height_nominal)) < 0.03
    assert np.max(np.abs(np.degrees(np.asarray(rec.base_rpy)[:, :2]))) < 3.0
    # The box was lifted off the table: held standing (3-5.5 s) it is more than 2 cm above
    # where it rested (the plan raises it 4 cm).
    holding = (t > 3.0) & (t < 5.5)
    rest_z = box.position[2]
    assert np.min(p_box[holding, 2]) > rest_z + 0.02
    # It ends on the table, at rest: its centre at the top plus half its height (1 cm for
    # contact), inside the table's footprint with a margin of half the box.
    top = table.size[2]
    end = p_box[-1]
    assert abs(end[2] - (top + box.size[2] / 2.0)) < 0.01
    assert abs(end[0] - table.position[0]) < table.size[0] / 2.0 - box.size[0] / 2.0
    assert abs(end[1] - table.position[1]) < table.size[1] / 2.0 - box.size[1] / 2.0
    assert np.linalg.norm(p_box[-1] - p_box[-10]) < 1e-3  # still over the last 0.09 s
    assert "box" not in rec.held_at_end
    # Torques MuJoCo applied stay within H1's limits (the elbows' 18 N m bind first).
    assert result.metrics["peak_torque_ratio"] <= 1.0
    assert result.metrics["passed"]
