"""Shared helpers of the compare tests: short task scripts, package-transfer geometries and
synthetic run traces (a RunRecord filled from the plan, no simulation) for plot and table
tests that must stay fast."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from locoplan.compare import Comparison, RunTrace, Variant, VariantOutcome, fixture_outlines
from locoplan.compare.trace import trace_from_run
from locoplan.compare.variants import comparison_variants, schedules_identical
from locoplan.plan import compile_plan
from locoplan.robot.description import load_robot_description
from locoplan.scenario import Scenario, load_scenario
from locoplan.sim.loop import RunRecord

SCENARIO_DIR = Path(__file__).resolve().parent.parent / "scenarios"

# Locomotion only: nothing to re-time, so both strategies compile the same schedule.
SHORT_TURN = """version: 1
name: short-turn
gait: {period: 0.4, swing: 0.15}
tasks:
  - {action: turn, angle: 45, start: 0.2, duration: 0.8}
end: 1.5
expect:
  no_fall: true
  max_torque_ratio: 1.0
"""

SHORT_STAND = """version: 1
name: short-stand
tasks:
  - {action: stand, start: 0.0, duration: 1.0}
end: 1.0
expect:
  no_fall: true
  max_torque_ratio: 1.0
"""

# A pick that waits for the turn to end: no overlap, so quasi-static moves nothing.
TURN_THEN_PICK = """version: 1
name: turn-then-pick
gait: {period: 0.4, swing: 0.15}
objects:
  package:
    shape: box
    size: [0.20, 0.20, 0.15]
    mass: 2.0
    position: [0.0, 0.35, 0.545]
fixtures:
  table:
    kind: table
    position: [0.0, 0.45, 0.0]
    size: [0.50, 0.40, 0.47]
tasks:
  - {action: turn, angle: 90, start: 0.0, duration: 1.6}
  - {action: pick, object: package, start: 1.8, duration: 1.0}
end: 3.5
expect:
  no_fall: true
"""


def package_transfer_yaml(side: float = 1.0, mass: float = 3.0, shift: float = 0.0) -> str:
    """The package-transfer script with its geometry mirrored (`side` -1: the table on the
    robot's right, turns reversed), another package `mass` (kg), or the table and package
    `shift` m further out and the conveyor `shift` m further ahead. Timings are the
    repository script's."""
    s, d = side, shift
    return f"""version: 1
name: package-transfer-variant
robot_start: {{position: [0.0, 0.0], yaw: 0}}
strategy: dynamic
model: external-force
gait: {{period: 0.4, swing: 0.15}}
objects:
  package:
    shape: box
    size: [0.20, 0.20, 0.15]
    mass: {mass}
    position: [0.0, {s * (0.35 + d):.4f}, 0.545]
fixtures:
  table:
    kind: table
    position: [0.0, {s * (0.45 + d):.4f}, 0.0]
    size: [0.34, 0.40, 0.47]
  conveyor:
    kind: conveyor
    position: [{0.35 + d:.4f}, 0.0, 0.0]
    size: [1.20, 0.35, 0.47]
    yaw: 90
    speed: 0.2
tasks:
  - {{action: turn, angle: {90 * s:g}, start: 0.0, duration: 1.6}}
  - {{action: pick, object: package, start: 0.9, duration: 1.0}}
  - {{action: turn, angle: {-90 * s:g}, start: 1.9, duration: 1.6}}
  - {{action: drop, object: package, onto: conveyor, start: 2.8, duration: 1.2}}
end: 4.6
expect:
  no_fall: true
  max_torque_ratio: 1.0
  placed: {{package: conveyor}}
"""


def repo_scenario_text(stem: str) -> tuple[Scenario, str]:
    """A scenario of scenarios/ and its text."""
    path = SCENARIO_DIR / f"{stem}.yaml"
    text = path.read_text("utf-8")
    return load_scenario(str(path), text), text


def synthetic_trace(
    scenario: Scenario, label: str, strategy: str, fall_at: float | None = None
) -> RunTrace:
    """A trace that follows the plan exactly (trunk on its reference, held objects on their
    planned centre, smooth torques at 60% of the limits), cut at `fall_at` (s) if given."""
    plan = compile_plan(scenario, strategy)
    desc = load_robot_description(scenario.robot)
    rec = RunRecord(
        joint_names=tuple(desc.joint_names), torque_limits=np.asarray(desc.torque_limits)
    )
    t_stop = plan.t_end if fall_at is None else fall_at
    t = np.arange(0.0, t_stop, 0.01)
    ref = plan.trunk_reference(t)
    obj_planned = plan.object_positions(t)
    held = plan.object_held(t)
    stance = plan.contact_flags(t)
    lim = np.asarray(desc.torque_limits)
    for n, tn in enumerate(t):
        rec.t.append(float(tn))
        rec.base_position.append(np.asarray(ref.position[n]))
        rec.base_rpy.append((0.0, 0.02, float(ref.yaw[n])))
        rec.joint_torque.append(0.6 * lim * np.sin(2 * np.pi * tn + np.arange(lim.size)))
        rec.stance.append((bool(stance[n, 0]), bool(stance[n, 1])))
    for name, o in scenario.objects.items():
        start = np.asarray(o.position, dtype=float)
        rec.object_positions[name] = [obj_planned[n] if held[n] else start for n in range(t.size)]
    rec.fall_time = fall_at
    rec.fell = fall_at is not None
    return trace_from_run(label, plan, rec, desc, None if fall_at else float(t_stop))


def synthetic_metrics(scenario: Scenario, variant: Variant, trace: RunTrace) -> dict[str, Any]:
    """A metrics object with the contract's keys, from a synthetic trace."""
    fell = trace.fall_time is not None
    return {
        "scenario": scenario.name,
        "strategy": variant.strategy,
        "model": variant.model,
        "sim_time": float(trace.t[-1]),
        "wall_time": 1.0,
        "real_time_factor": 1.5,
        "completed": not fell,
        "completion_time": trace.completion_time,
        "fell": fell,
        "fall_time": trace.fall_time,
        "yaw_difference_deg": trace.yaw_difference_deg,
        "peak_torque_ratio": 0.6,
        "peak_torque_joint": "L_knee",
        "peak_torque": {},
        "final_base": {"position": [0.0, 0.0, 0.6], "yaw_deg": 0.0},
        "objects": {
            name: {"position": [0.0, 0.0, 0.5], "on": "conveyor", "held": False}
            for name in scenario.objects
        },
        "mpc_solve_ms": {"median": 1.0, "p99": 2.0, "count": 100},
        "wbc_solve_ms": {"median": 0.1, "p99": 0.2, "count": 1000},
        "expectations": {"no_fall": {"ok": not fell, "value": fell, "limit": True}},
        "passed": not fell,
        "log": None,
    }


def synthetic_comparison(
    scenario: Scenario, kind: str = "strategies", fall_at: float | None = None
) -> Comparison:
    """A comparison of synthetic runs (no simulation); with `fall_at` the baseline falls."""
    variants = comparison_variants(scenario, kind)  # type: ignore[arg-type]
    outcomes = []
    for i, v in enumerate(variants):
        tr = synthetic_trace(scenario, v.label, v.strategy, fall_at if i == 0 else None)
        outcomes.append(VariantOutcome(v, synthetic_metrics(scenario, v, tr), tr, None, None))
    plans = [compile_plan(scenario, v.strategy) for v in variants]
    return Comparison(
        scenario_name=scenario.name,
        kind=kind,  # type: ignore[arg-type]
        outcomes=(outcomes[0], outcomes[1]),
        schedules_identical=schedules_identical(plans[0], plans[1]),
        schedule_note=None,
        mpc_dt=scenario.mpc.dt,
        fixtures=fixture_outlines(scenario),
        out_dir=Path("."),
    )
