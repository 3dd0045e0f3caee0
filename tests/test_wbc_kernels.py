"""The compiled WBC kernels: compiled once, for the argument types the control loop passes."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from locoplan.control import qp, wbc_kernels
from locoplan.control.controller import joint_wall_rows
from locoplan.control.wbc import TASK_DAMPING, prioritized_rows
from locoplan.plan import compile_plan
from locoplan.robot.description import load_robot_description
from locoplan.scenario import load_scenario_file
from locoplan.sim.loop import ClosedLoop
from locoplan.sim.run import RunOptions, controller_settings, scene_for

ROOT = Path(__file__).resolve().parents[1]
KERNELS = ("stack_tasks", "prioritized", "lean_build", "lean_finish", "prioritized_walled")


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


def test_the_walled_stack_is_the_three_calls_to_the_bit() -> None:
    """`prioritized_walled` (one compiled call in the controller's tick) against what the
    controller did before: `prioritized_rows`, `joint_wall_rows` on its result and, for the
    walled joints, `prioritized_rows` again on the stack with a unit row each on top (r the
    wall acceleration). Random well-posed stacks of three levels on 16 joints, walls on two
    of them set so that about half the draws hit a wall: equal bit for bit, hit or not."""
    rng = np.random.default_rng(7)
    nv = 22
    cols = np.array([17, 20], dtype=np.intp)
    hits = 0
    for _ in range(40):
        J = rng.standard_normal((14, nv))
        a, b = rng.standard_normal(14), rng.standard_normal(14)
        ends = np.array([6, 10, 14], dtype=np.int64)
        q = rng.standard_normal(nv + 1)
        v = rng.standard_normal(nv)
        lower = q[cols + 1] - rng.uniform(0.0, 0.2, 2)
        upper = q[cols + 1] + rng.uniform(0.0, 0.2, 2)
        decel = np.array([30.0, 50.0])
        qdd, hit, acc = wbc_kernels.prioritized_walled(
            J, a, b, ends, TASK_DAMPING, cols, lower, upper, q, v, decel, 0.05
        )
        want = prioritized_rows(J, a - b, ends)
        want_hit, want_acc = joint_wall_rows(cols, lower, upper, q, v, want, decel, 0.05)
        if len(want_hit):
            hits += 1
            n = len(want_hit)
            rows = np.zeros((n, nv))
            rows[np.arange(n), want_hit] = 1.0
            J_w = np.vstack((rows, J))
            r_w = np.concatenate((want_acc, a)) - np.concatenate((np.zeros(n), b))
            want = prioritized_rows(J_w, r_w, np.concatenate(([n], ends + n)).astype(np.int64))
        np.testing.assert_array_equal(hit, want_hit)
        np.testing.assert_array_equal(acc, want_acc)
        assert qdd.tobytes() == want.tobytes()
    assert 5 <= hits <= 35
