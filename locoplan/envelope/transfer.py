"""The transfer family (issue 12, first row of the envelope): turn towards a table, pick a box
during the turn's last half, turn back, drop it onto a platform or a conveyor during that
turn's second half. Laid out like the issue's transfer examples: the robot starts at the
origin facing +x, the table lies in the direction the first turn ends in, facing the robot,
and the target in the direction the robot faces after both turns.
"""

from __future__ import annotations

from locoplan.envelope import ranges as rg
from locoplan.envelope.compose import (
    Doc,
    Draw,
    NoLayout,
    end_after,
    expectations,
    fits,
    rect_of,
    rt,
    table_with_object,
    target,
    turn_limit_deg,
    wrap_deg,
)

GEOMETRY_TRIES = 20


def transfer(d: Draw, name: str) -> Doc:
    """One transfer script (raises NoLayout when its draws admit no scene)."""
    gait = d.manip_gait()
    period = gait["period"]
    sign = d.sign()
    turn1 = sign * d.angle(*rg.TRANSFER_TURN1)
    turn2 = -sign * d.angle(*rg.TRANSFER_TURN2)
    t1, d1 = 0.0, d.duration(turn1, rg.TRANSFER_TURN_RATE, period, turn_limit_deg(d, period))
    t1_end = rt(t1 + d1)
    pick = d.time(t1 + d1 / 2, t1_end)
    pick_d = d.time(*rg.PICK_DURATION)
    pick_end = rt(pick + pick_d)
    t2 = max(t1_end, pick_end)
    d2 = d.duration(turn2, rg.TRANSFER_TURN_RATE, period, turn_limit_deg(d, period))
    t2_end = rt(t2 + d2)
    drop = d.time(t2 + d2 / 2, t2_end)
    drop_d = d.time(*rg.DROP_DURATION)
    tasks = [
        {"action": "turn", "angle": turn1, "start": t1, "duration": d1},
        {"action": "pick", "object": "parcel", "start": pick, "duration": pick_d},
        {"action": "turn", "angle": turn2, "start": t2, "duration": d2},
        {"action": "drop", "object": "parcel", "onto": "TARGET", "start": drop, "duration": drop_d},
    ]
    end = end_after(tasks)
    mass = d.mass(d.r.transfer_mass)
    yaw1, yaw2 = wrap_deg(turn1), wrap_deg(turn1 + turn2)
    kind = d.choice(("platform", "conveyor"))
    for _ in range(GEOMETRY_TRIES):
        placed = table_with_object(d, (0.0, 0.0), yaw1, mass)
        extent = max(placed.obj["size"][:2])
        goal = target(d, (0.0, 0.0), yaw2, kind, extent, travel=end - drop)
        fixtures = [rect_of(placed.table), rect_of(goal)]
        if fits(d, fixtures, [(0.0, 0.0)], [rect_of(placed.obj)]) and fits(
            d, [rect_of(placed.obj), fixtures[1]], [(0.0, 0.0)]
        ):
            break
    else:
        raise NoLayout("table and target overlap")
    tasks[3]["onto"] = kind
    speed = f", belt {goal['speed']:.2f} m/s" if kind == "conveyor" else ""
    return {
        "version": 1,
        "name": name,
        "description": (
            f"generated (transfer): turn {turn1:+.1f} deg in {d1:.2f} s, pick {mass:.2f} kg "
            f"at {pick:.2f} s, turn {turn2:+.1f} deg in {d2:.2f} s, drop onto the {kind}"
            f"{speed} at {drop:.2f} s"
        ),
        "gait": gait,
        "objects": {"parcel": placed.obj},
        "fixtures": {"table": placed.table, kind: goal},
        "tasks": tasks,
        "end": end,
        "expect": expectations({"parcel": kind}),
    }
