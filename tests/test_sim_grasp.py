"""locoplan.sim.grasp in MuJoCo: the measured hand load and the palm bond, asserted from the
simulation state of a real closed loop (scenarios/model-comparison.yaml: a 5 kg block picked
from a table in front and held standing)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from locoplan.log.reader import read_log
from locoplan.plan import compile_plan
from locoplan.robot.description import load_robot_description
from locoplan.scenario import load_scenario_file
from locoplan.sim.grasp import PALM_BOND_DEFLECTION, PALM_BOND_FREQUENCY, palm_bond_frequency
from locoplan.sim.loop import ClosedLoop
from locoplan.sim.run import RunOptions, controller_settings, run_scenario, scene_for

pytestmark = pytest.mark.closed_loop

ROOT = Path(__file__).resolve().parents[1]
GRAVITY = 9.81


def test_hand_load_reads_the_weight_and_the_palm_bond_keeps_the_block_level() -> None:
    loaded = load_scenario_file(ROOT / "scenarios" / "model-comparison.yaml")
    scenario = loaded.scenario
    desc = load_robot_description(scenario.robot)
    plan = compile_plan(scenario)
    scene = scene_for(scenario, desc)
    loop = ClosedLoop(scene, desc, plan, controller_settings(scenario, RunOptions()))
    rec = loop.run(4.0)
    assert not rec.fell
    name = next(iter(scenario.objects))
    mass = scenario.objects[name].mass
    d = loop.backend.data
    body = scene.object_body_ids[name]
    # Held still, off the table: the grasps carry the block's weight. Tolerance 10 %: the
    # hands still move a little (the load's inertia, m a, is in the reading too).
    assert loop.grasp.held_objects() == {name}
    assert loop.grasp.hand_load(d) == pytest.approx(mass * GRAVITY, rel=0.10)
    # The palm bond holds the block's attitude: it was level on the table and stays within a
    # few degrees of level (tilt of its z axis).
    R = d.xmat[body].reshape(3, 3)
    tilt = math.degrees(math.acos(min(1.0, float(R[2, 2]))))
    assert tilt < 5.0
    # Nothing else holds it: no contact between the block and the table.
    table = scene.fixture_geom_ids[next(iter(scenario.fixtures))]
    geom = scene.object_geom_ids[name]
    pairs = {tuple(sorted((int(c.geom1), int(c.geom2)))) for c in d.contact[: d.ncon]}
    assert tuple(sorted((geom, table))) not in pairs
    # The bond's torque on the block is matched by the opposite torque on the hands.
    hands = [scene.hand_body_ids[k] for k in range(2)]
    total = d.xfrc_applied[body, 3:6] + sum(d.xfrc_applied[h, 3:6] for h in hands)
    assert np.allclose(total, 0.0, atol=1e-9)


def test_a_small_box_gripped_behind_its_centre_hangs_nearly_level(tmp_path: Path) -> None:
    """HECTOR envelope seed 73021's transfer-004 (tests/data/small-box-gripped-behind.yaml):
    a 5.83 kg box of 0.11-0.12 m, gripped 2.5 cm nearer the robot than its centre, whose
    weight's moment about the grip line the palm bond holds with I w^2, I its small own
    inertia (`PALM_BOND_FREQUENCY`). At 20 rad/s it hung 15-18 deg nose-down from the lift on,
    its far bottom corner caught the 0.548 m platform's edge in the turn towards it, and the
    robot fell; now it stays within 6 deg of level while carried (measured 2.6-3.9, asserted
    from the log's simulator state: the angle of its z axis from the vertical, from 0.3 s
    after the lift-off to the drop's start) and is placed on the platform."""
    loaded = load_scenario_file(ROOT / "tests" / "data" / "small-box-gripped-behind.yaml")
    result = run_scenario(loaded.scenario, loaded.text, RunOptions(out_dir=tmp_path))
    (hold,) = result.plan.holds
    assert hold.grip_behind > 0.02
    assert result.log_path is not None
    states = list(read_log(result.log_path).messages("/sim/qpos"))
    t = np.array([s[0] for s in states])
    quat = np.array([s[1]["qpos"][-4:] for s in states])
    tilt = np.degrees(np.arccos(np.clip(1.0 - 2.0 * (quat[:, 1] ** 2 + quat[:, 2] ** 2), -1, 1)))
    drop_start = loaded.scenario.tasks[3].start
    carried = (t > hold.lift + 0.3) & (t < drop_start)
    assert np.count_nonzero(carried) > 100
    assert np.max(tilt[carried]) < 6.0
    assert not result.metrics["fell"]
    assert result.metrics["objects"]["parcel"]["on"] == "platform"


def test_the_palm_bond_stiffens_for_an_object_gripped_off_its_centre() -> None:
    """`palm_bond_frequency`: PALM_BOND_FREQUENCY for an object gripped over its centre (and
    for any grip the base frequency already holds within PALM_BOND_DEFLECTION); for a 0.10 m
    cube of 6 kg gripped 3 cm behind its centre (I = m (0.1^2 + 0.1^2) / 12 about the grip
    line) the stiffness I w^2 holds the weight's moment m g d at exactly PALM_BOND_DEFLECTION
    (to 1e-12 relative); the 20 rad/s bond would let it deflect 25 deg."""
    assert palm_bond_frequency(14.0, 0.09, 0.0) == PALM_BOND_FREQUENCY
    assert palm_bond_frequency(14.0, 0.09, 0.005) == PALM_BOND_FREQUENCY
    mass, inertia, d = 6.0, 6.0 * 0.02 / 12.0, 0.03
    w = palm_bond_frequency(mass, inertia, d)
    assert w > PALM_BOND_FREQUENCY
    assert mass * GRAVITY * d / (inertia * w * w) == pytest.approx(PALM_BOND_DEFLECTION, rel=1e-12)
    at_base = mass * GRAVITY * d / (inertia * PALM_BOND_FREQUENCY**2)
    assert math.degrees(at_base) == pytest.approx(25.3, abs=0.1)


def test_weld_forces_take_each_welds_third_row_or_nan() -> None:
    """`hand_load`'s kernel: for each weld (an equality id), the force of its third equality
    row in row order (a `connect`'s world z row), NaN unless it has exactly three rows; the
    count of equality rows (0: `hand_load` reads no load at all)."""
    from locoplan.sim.grasp import _EQUALITY, _weld_forces

    other = _EQUALITY + 1
    efc_type = np.array([other, _EQUALITY, _EQUALITY, other, _EQUALITY, _EQUALITY, _EQUALITY,
                         _EQUALITY, _EQUALITY], dtype=np.int32)  # fmt: skip
    efc_id = np.array([7, 4, 4, 4, 4, 9, 9, 9, 9], dtype=np.int32)
    efc_force = np.arange(9, dtype=np.float64) * 1.5
    welds = np.array([4, 9, 12], dtype=np.int64)
    out = np.zeros(3)
    assert _weld_forces(efc_type, efc_id, efc_force, _EQUALITY, welds, out) == 7
    # Weld 4: equality rows 1, 2, 4 (row 3 is another type): the third is row 4. Weld 9: four
    # rows, not a connect's three: NaN. Weld 12: none.
    assert out[0] == 6.0
    assert np.isnan(out[1]) and np.isnan(out[2])
    none = np.array([other] * 3, dtype=np.int32)
    assert _weld_forces(none, efc_id[:3], efc_force[:3], _EQUALITY, welds, out) == 0
