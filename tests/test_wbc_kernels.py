"""The compiled WBC kernels: compiled once, for the argument types the control loop passes."""

from __future__ import annotations

import math
from pathlib import Path

from locoplan.control import qp, wbc_kernels
from locoplan.plan import compile_plan
from locoplan.robot.description import load_robot_description
from locoplan.scenario import load_scenario_file
from locoplan.sim.loop import ClosedLoop
from locoplan.sim.run import RunOptions, controller_settings, scene_for

ROOT = Path(__file__).resolve().parents[1]
KERNELS = ("stack_tasks", "prioritized", "lean_build", "lean_finish")


def test_the_loop_uses_the_warmed_up_signatures() -> None:
    """A second signature would mean a compilation (seconds) inside the control loop: the
    controller's warm-up must cover the exact argument types (layout, read-only flags) of
    the calls in `step`, through a swing and both stance configurations."""
    sc = load_scenario_file(ROOT / "scenarios" / "step.yaml").scenario
    plan = compile_plan(sc, None)
    desc = load_robot_description(sc.robot)
    start = sc.robot_start
    loop = ClosedLoop(
        scene_for(sc, desc),
        desc,
        plan,
        controller_settings(sc, RunOptions(log=False)),
        start_xy=(start.position[0], start.position[1]),
        start_yaw=math.radians(start.yaw),
    )
    # At least the warm-up's (other tests in this process may have compiled more).
    before = {name: len(getattr(wbc_kernels, name).signatures) for name in KERNELS}
    before["meets_rows"] = len(qp._meets_rows.signatures)
    assert min(before.values()) >= 1
    rec = loop.run(1.0)
    assert not rec.fell
    assert any(not all(s) for s in rec.stance)  # a foot swung
    after = {name: len(getattr(wbc_kernels, name).signatures) for name in KERNELS}
    after["meets_rows"] = len(qp._meets_rows.signatures)
    assert after == before
