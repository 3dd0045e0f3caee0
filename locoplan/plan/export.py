"""JSON-ready export of a plan (`locoplan plan --json`). Angles in degrees here, for people."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from locoplan.plan.plan import Plan

FORMAT_VERSION = 1


def _t(x: float, t_end: float) -> float:
    """A time for JSON: infinity (held to the end) becomes t_end."""
    return round(min(x, t_end), 9)


def _r(x: float) -> float:
    return round(float(x), 9)


def plan_to_dict(plan: Plan, reference_dt: float = 0.02) -> dict[str, Any]:
    """The plan as plain dicts/lists: tasks, gait fits, per-foot and per-hand phases, object
    holds and targets, events, a reference summary and the trunk reference sampled every
    `reference_dt` s (yaw in degrees)."""
    te = plan.t_end
    feet: dict[str, Any] = {}
    for f in ("L", "R"):
        feet[f] = {
            "stance": [[_r(a), _r(b)] for a, b in plan.stance_intervals(f)],
            "swing": [[_r(a), _r(b)] for a, b in plan.swing_intervals(f)],
        }
    hands: dict[str, Any] = {}
    for h_index, h in enumerate(("L", "R")):
        track = plan.manipulation.tracks[h_index]
        hands[h] = {
            "contact": [
                {"object": c.object, "t0": _t(c.t0, te), "t1": _t(c.t1, te)}
                for c in plan.manipulation.contacts[h_index]
            ],
            "active": [
                [_t(a, te), _t(b, te)]
                for a, b in plan.manipulation.active_intervals[h_index].as_tuples()
            ],
            "segments": [
                {
                    "t0": _r(g.t0),
                    "t1": _r(g.t1),
                    "phase": g.label,
                    "task": g.task_index,
                    "start": {"frame": g.start.frame, "point": [_r(v) for v in g.start.point]},
                    "end": {
                        "frame": g.end.frame,
                        "point": [_r(v) for v in g.end.point],
                        "velocity": [_r(v) for v in g.end.velocity],
                    },
                }
                for g in track.segments
            ],
        }
    objects = {
        name: {
            "kind": tgt.kind,
            "position": None if tgt.position is None else [_r(v) for v in tgt.position],
            "yaw_deg": None if tgt.yaw is None else _r(math.degrees(tgt.yaw)),
            "fixture": tgt.fixture,
            "time": None if tgt.time is None else _r(tgt.time),
        }
        for name, tgt in plan.manipulation.targets.items()
    }
    x, y, yaw = plan.final_pose
    n = max(2, math.floor(te / reference_dt + 1e-9) + 1)
    times = np.linspace(0.0, reference_dt * (n - 1), n)
    ref = plan.trunk_reference(times)
    return {
        "format": FORMAT_VERSION,
        "scenario": plan.scenario_name,
        "strategy": plan.strategy,
        "t_end": _r(te),
        "end_shift": _r(plan.end_shift),
        "base_height": plan.base_height,
        "foot_width": plan.foot_width,
        "gait": {
            "period": plan.gait_period,
            "swing": plan.gait_swing,
            "blocks": [
                {
                    "task": b.task_index,
                    "start": _r(b.start),
                    "end": _r(b.end),
                    "cycles": b.cycles,
                    "period": _r(b.period),
                    "swing": _r(b.swing),
                }
                for b in plan.contacts.blocks
            ],
        },
        "notes": list(plan.notes),
        "tasks": [
            {
                "index": t.index,
                "action": t.action,
                "start": _r(t.start),
                "end": _r(t.end),
                "shift": _r(t.shift),
                **({"object": t.object} if t.object is not None else {}),
                **({"hands": t.hands} if t.hands is not None else {}),
                **({"distance": list(t.distance)} if t.distance is not None else {}),
                **({"angle_deg": _r(math.degrees(t.angle))} if t.angle is not None else {}),
                **({"onto": t.onto} if t.onto is not None else {}),
                **({"at": list(t.at)} if t.at is not None else {}),
                **({"velocity": list(t.velocity)} if t.velocity is not None else {}),
            }
            for t in plan.tasks
        ],
        "feet": feet,
        "hands": hands,
        "holds": [
            {
                "object": h.object,
                "mass": h.mass,
                "hands": list(h.hands),
                "pick_task": h.pick_task,
                "grasp": _t(h.grasp, te),
                "lift": _t(h.lift, te),
                "release": _t(h.release, te),
                "release_task": h.release_task,
                "release_kind": h.release_kind,
                "pre_lean": h.pre_lean,
                "grip_behind": h.grip_behind,
                "slow_lift": h.slow_lift,
            }
            for h in plan.holds
        ],
        "objects": objects,
        "events": [
            {"t": _r(e.t), "kind": e.kind, "task": e.task_index, "detail": e.detail}
            for e in plan.events
        ],
        "summary": {
            "final_position": [_r(x), _r(y), plan.base_height],
            "final_yaw_deg": _r(math.degrees(yaw)),
            "total_time": _r(te),
        },
        "reference": {
            "dt": reference_dt,
            "t": [_r(v) for v in times],
            "position": [[_r(v) for v in row] for row in ref.position],
            "yaw_deg": [_r(math.degrees(v)) for v in ref.yaw],
        },
    }
