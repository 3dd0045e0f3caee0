"""locoplan.sim.grasp in MuJoCo: the measured hand load and the palm bond, asserted from the
simulation state of a real closed loop (scenarios/model-comparison.yaml: a 5 kg block picked
from a table in front and held standing)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from locoplan.plan import compile_plan
from locoplan.robot.description import load_robot_description
from locoplan.scenario import load_scenario_file
from locoplan.sim.loop import ClosedLoop
from locoplan.sim.run import RunOptions, controller_settings, scene_for

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
