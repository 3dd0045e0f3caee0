"""The carrying families of issue 12's envelope: walk-carry, side-carry and standing hold.

Each picks a box from a table in front of the robot (near side NEAR_SIDE away, top
TABLE_TOP high, as in scenarios/standing-load.yaml and pick-walk-drop.yaml) and places it:
after a turn and a forward walk (walk-carry), after a side-step (side-carry), or back on the
same table after holding it standing (standing hold).
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
    walk_limit,
    wrap_deg,
)
from locoplan.envelope.geometry import rects_apart

GEOMETRY_TRIES = 20
# m: side-carry keeps the table and the platform this far apart across the step, plus the
# rounding of their positions to 1 mm (FIXTURE_GAP and some).
SIDE_GAP = 0.024


def walk_carry(d: Draw, name: str) -> Doc:
    """Pick from a table in front, turn up to WALK_CARRY_TURN (starting up to 0.3 s before
    the pick ends), walk WALK_CARRY_DISTANCE forward, place on a platform whose near edge is
    TARGET_NEAR_EDGE ahead of the walk's end (the drop may start before the walk ends).

    Laid out like pick-walk-drop.yaml: the robot starts facing the table at yaw -turn, so
    that it walks along +x. Turns too small to clear the table's corner with the robot's
    footprint on the walk are drawn again (in practice |turn| >= about 60 deg)."""
    gait = d.manip_gait()
    period = gait["period"]
    turn = d.sign() * d.angle(*rg.WALK_CARRY_TURN)
    yaw0 = wrap_deg(-turn)
    mass = d.mass(d.r.walk_carry_mass)
    pick, pick_d = 0.5, d.time(*rg.PICK_DURATION)
    pick_end = rt(pick + pick_d)
    tasks: list[Doc] = [{"action": "pick", "object": "box", "start": pick, "duration": pick_d}]
    walk = pick_end
    if abs(turn) >= 0.05:
        turn_start = rt(pick_end - d.time(*rg.WALK_CARRY_TURN_LEAD))
        turn_d = d.duration(turn, rg.WALK_CARRY_TURN_RATE, period, turn_limit_deg(d, period))
        tasks.append({"action": "turn", "angle": turn, "start": turn_start, "duration": turn_d})
        walk = rt(turn_start + turn_d)
    walk = rt(walk + d.time(0.0, 0.3))
    distance = d.length(*rg.WALK_CARRY_DISTANCE)
    walk_d = d.duration(distance, rg.WALK_CARRY_SPEED, period, walk_limit(d, period))
    walk_end = rt(walk + walk_d)
    tasks.append({"action": "walk", "distance": [distance, 0.0], "start": walk, "duration": walk_d})
    drop = max(pick_end, rt(walk_end - d.time(*rg.WALK_CARRY_DROP_LEAD)))
    drop_d = d.time(*rg.DROP_DURATION)
    tasks.append(
        {"action": "drop", "object": "box", "onto": "platform", "start": drop, "duration": drop_d}
    )
    path = [(0.0, 0.0), (distance, 0.0)]
    for _ in range(GEOMETRY_TRIES):
        placed = table_with_object(d, (0.0, 0.0), yaw0, mass)
        goal = target(d, (distance, 0.0), 0.0, "platform", max(placed.obj["size"][:2]))
        box = rect_of(placed.obj)
        if fits(d, [rect_of(placed.table), rect_of(goal)], path, [box]) and fits(
            d, [box, rect_of(goal)], path[:1]
        ):
            break
    else:
        raise NoLayout("the walk runs into the table")
    return {
        "version": 1,
        "name": name,
        "description": (
            f"generated (walk-carry): pick {mass:.2f} kg, turn {turn:+.1f} deg, walk "
            f"{distance:.3f} m in {walk_d:.2f} s, drop onto the platform at {drop:.2f} s"
        ),
        "robot_start": {"position": [0.0, 0.0], "yaw": yaw0},
        "gait": gait,
        "objects": {"box": placed.obj},
        "fixtures": {"table": placed.table, "platform": goal},
        "tasks": tasks,
        "end": end_after(tasks),
        "expect": expectations({"box": "platform"}),
    }


def side_carry(d: Draw, name: str) -> Doc:
    """Pick from a table in front, side-step SIDE_STEP left or right (walk [0, +-d]) at up
    to SIDE_SPEED, place on a platform in front of the final position.

    The table and the platform stand side by side, so their widths across the step must
    fit in twice the step: FIXTURE_SIDE where that allows, else (steps under about 0.31 m)
    as narrow as the box's width plus 3 cm (table) or 5 cm (platform). The platform keeps
    `hand_room` from the box's side: the hand waits between them before the grasp."""
    gait = d.manip_gait()
    period = gait["period"]
    side = d.sign() * d.length(*rg.SIDE_STEP)
    mass = d.mass(d.r.side_mass)
    pick, pick_d = 0.5, d.time(*rg.PICK_DURATION)
    pick_end = rt(pick + pick_d)
    walk = rt(pick_end + d.time(0.0, 0.3))
    walk_d = d.duration(side, rg.SIDE_SPEED, period, walk_limit(d, period))
    drop = rt(walk + walk_d + d.time(0.0, 0.3))
    drop_d = d.time(*rg.DROP_DURATION)
    tasks: list[Doc] = [
        {"action": "pick", "object": "box", "start": pick, "duration": pick_d},
        {"action": "walk", "distance": [0.0, side], "start": walk, "duration": walk_d},
        {"action": "drop", "object": "box", "onto": "platform", "start": drop, "duration": drop_d},
    ]
    room = 2 * abs(side) - SIDE_GAP
    lo, hi = rg.FIXTURE_SIDE
    widths: dict[str, float] = {}

    def table_width(across: float) -> float:
        least = lo if room >= 2 * lo else across + 0.03
        widths["box"] = across
        return d.length(least, min(hi, room - max(least, across + 0.05)))

    path = [(0.0, 0.0), (0.0, side)]
    for _ in range(GEOMETRY_TRIES):
        placed = table_with_object(d, (0.0, 0.0), 0.0, mass, width=table_width)
        free = room - placed.table["size"][1]
        least = lo if free >= lo else widths["box"] + 0.05
        width = d.length(least, min(hi, free))
        goal = target(d, (0.0, side), 0.0, "platform", max(placed.obj["size"][:2]), width=width)
        box, goal_rect = rect_of(placed.obj), rect_of(goal)
        if (
            fits(d, [rect_of(placed.table), goal_rect], path, [box])
            and fits(d, [box, goal_rect], path[:1])
            and rects_apart(box, goal_rect, d.r.hand_room)
        ):
            break
    else:
        raise NoLayout("table and platform overlap")
    return {
        "version": 1,
        "name": name,
        "description": (
            f"generated (side-carry): pick {mass:.2f} kg, side-step {side:+.3f} m in "
            f"{walk_d:.2f} s, drop onto the platform at {drop:.2f} s"
        ),
        "gait": gait,
        "objects": {"box": placed.obj},
        "fixtures": {"table": placed.table, "platform": goal},
        "tasks": tasks,
        "end": end_after(tasks),
        "expect": expectations({"box": "platform"}),
    }


def standing_hold(d: Draw, name: str) -> Doc:
    """Stand 0.5 s, pick HOLD_MASS from a table in front, hold it standing HOLD_TIME, put it
    back on the same table (like issue 12's hold-11kg example)."""
    gait = d.manip_gait()
    mass = d.mass(d.r.hold_mass)
    pick, pick_d = 0.5, d.time(*rg.PICK_DURATION)
    hold = rt(pick + pick_d)
    hold_d = d.time(*rg.HOLD_TIME)
    drop = rt(hold + hold_d)
    drop_d = d.time(*rg.DROP_DURATION)
    tasks: list[Doc] = [
        {"action": "stand", "start": 0.0, "duration": pick},
        {"action": "pick", "object": "block", "start": pick, "duration": pick_d},
        {"action": "stand", "start": hold, "duration": hold_d},
        {"action": "drop", "object": "block", "onto": "table", "start": drop, "duration": drop_d},
    ]
    placed = table_with_object(d, (0.0, 0.0), 0.0, mass)
    if not fits(d, [rect_of(placed.table)], [(0.0, 0.0)], [rect_of(placed.obj)]):
        raise NoLayout("table on the robot")
    return {
        "version": 1,
        "name": name,
        "description": (
            f"generated (standing-hold): pick {mass:.2f} kg, hold {hold_d:.2f} s, put it back"
        ),
        "gait": gait,
        "objects": {"block": placed.obj},
        "fixtures": {"table": placed.table},
        "tasks": tasks,
        "end": end_after(tasks),
        "expect": expectations({"block": "table"}),
    }
