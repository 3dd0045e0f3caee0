"""The locomotion and throw families of issue 12's envelope.

Locomotion: 2-4 walks, turns and steps, back to back or with pauses, in an empty scene.
Throw: pick a sphere from a table in front (like scenarios/throw.yaml) and throw it forward,
standing or while stepping in place (a step task that overlaps the throw).
"""

from __future__ import annotations

import math

from locoplan.envelope import ranges as rg
from locoplan.envelope.compose import (
    Doc,
    Draw,
    NoLayout,
    end_after,
    expectations,
    fits,
    rect_of,
    rl,
    rt,
    table_with_object,
    turn_limit_deg,
    walk_limit,
    within_gait,
)

# Odds of each locomotion task kind.
LOCO_KINDS = (("walk", 0.45), ("turn", 0.35), ("step", 0.20))


def _loco_task(d: Draw, kind: str, period: float) -> Doc:
    if kind == "walk":
        length = d.length(*rg.LOCO_WALK_DISTANCE)
        heading = math.radians(d.angle(-180.0, 180.0))
        dx, dy = rl(length * math.cos(heading)), rl(length * math.sin(heading))
        length = math.hypot(dx, dy)
        task: Doc = {"action": "walk", "distance": [dx, dy]}
        angle = d.sign() * d.angle(*rg.LOCO_WALK_ANGLE) if d.chance(0.5) else 0.0
        duration = d.duration(length, rg.LOCO_WALK_SPEED, period, walk_limit(d, period))
        if angle:
            task["angle"] = angle
            while abs(angle) / duration > rg.LOCO_TURN_RATE:
                duration = rt(duration + 0.01)
            duration = within_gait(duration, angle, turn_limit_deg(d, period))
        task["duration"] = duration
        return task
    if kind == "turn":
        angle = d.sign() * d.angle(*rg.LOCO_TURN)
        return {
            "action": "turn",
            "angle": angle,
            "duration": d.duration(angle, rg.LOCO_TURN_RATE, period, turn_limit_deg(d, period)),
        }
    return {"action": "step", "duration": d.time(rg.LOCO_STEP[0], rg.LOCO_STEP[1])}


def locomotion(d: Draw, name: str) -> Doc:
    """LOCO_TASKS walks (LOCO_WALK_DISTANCE in any direction at up to LOCO_WALK_SPEED, half
    of them turning by up to LOCO_WALK_ANGLE on the way), turns (LOCO_TURN at up to
    LOCO_TURN_RATE) and steps (LOCO_STEP), each gap between them either none (back to back)
    or a LOCO_PAUSE of standing; gait period LOCO_PERIOD, swing LOCO_SWING_FRACTION of it."""
    gait = d.loco_gait()
    count = int(d.rng.integers(rg.LOCO_TASKS[0], rg.LOCO_TASKS[1] + 1))
    names = [k for k, _ in LOCO_KINDS]
    odds = [p for _, p in LOCO_KINDS]
    t = d.time(0.0, 0.5)
    tasks: list[Doc] = []
    for i in range(count):
        kind = names[int(d.rng.choice(len(names), p=odds))]
        task = _loco_task(d, kind, gait["period"])
        if i > 0 and d.chance(0.5):
            t = rt(t + d.time(*rg.LOCO_PAUSE))
        tasks.append({"action": task.pop("action"), **task, "start": t})
        tasks[-1]["duration"] = tasks[-1].pop("duration")
        t = rt(t + task["duration"])
    summary = ", ".join(str(task["action"]) for task in tasks)
    return {
        "version": 1,
        "name": name,
        "description": f"generated (locomotion): {summary}",
        "gait": gait,
        "tasks": tasks,
        "end": end_after(tasks),
        "expect": expectations(),
    }


def throw(d: Draw, name: str) -> Doc:
    """Pick a sphere (BALL_RADIUS, THROW_MASS) from a table in front, wait THROW_DELAY,
    throw it at (THROW_VX, THROW_VY, THROW_VZ) body frame in THROW_DURATION; half the
    scripts step in place meanwhile, from 0.2-0.6 s before the throw to 0-0.5 s after it
    (throw.yaml: 0.5 s before, 0.1 s after)."""
    gait = d.manip_gait()
    mass = d.mass(d.r.throw_mass)
    velocity = [
        d.speed(*rg.THROW_VX),
        d.speed(*rg.THROW_VY),
        d.speed(*rg.THROW_VZ),
    ]
    pick, pick_d = 0.5, d.time(*rg.PICK_DURATION)
    pick_end = rt(pick + pick_d)
    start = rt(pick_end + d.time(*rg.THROW_DELAY))
    duration = d.time(*rg.THROW_DURATION)
    tasks: list[Doc] = [{"action": "pick", "object": "ball", "start": pick, "duration": pick_d}]
    stepping = d.chance(0.5)
    if stepping:
        step = max(pick_end, rt(start - d.time(0.2, 0.6)))
        step_end = rt(start + duration + d.time(0.0, 0.5))
        tasks.append({"action": "step", "start": step, "duration": rt(step_end - step)})
    throw_task = {"action": "throw", "object": "ball", "velocity": velocity}
    tasks.append({**throw_task, "start": start, "duration": duration})
    placed = table_with_object(d, (0.0, 0.0), 0.0, mass, shape="sphere")
    if not fits(d, [rect_of(placed.table)], [(0.0, 0.0)], [rect_of(placed.obj)]):
        raise NoLayout("table on the robot")
    how = "while stepping" if stepping else "standing"
    return {
        "version": 1,
        "name": name,
        "description": (
            f"generated (throw): pick a {mass:.2f} kg ball, throw it at "
            f"[{velocity[0]:.2f}, {velocity[1]:.2f}, {velocity[2]:.2f}] m/s {how}"
        ),
        "gait": gait,
        "objects": {"ball": placed.obj},
        "fixtures": {"table": placed.table},
        "tasks": tasks,
        "end": end_after(tasks),
        "expect": expectations(),
    }
