"""The envelope the generator draws from: issue 12's table, one constant per range.

Every range here is inclusive and drawn uniformly on a grid (times 0.01 s, lengths 1 mm,
angles 0.1 deg, masses 0.01 kg). Where issue 12 gives only an upper bound on a rate ("at up
to 65 deg/s"), the rate is drawn from [RATE_FLOOR x max, max]: slower tasks are easier and
the paper's timings sit in that band (package-transfer turns at 56 deg/s, pick-walk-drop
walks at 0.25 m/s). A task's duration is its angle or distance over the drawn rate, rounded
up to 0.01 s (so the rate never exceeds the maximum), and never shorter than one gait period.
"""

from __future__ import annotations

Range = tuple[float, float]

# Fraction of a rate's maximum that its draws start from (see the module docstring).
RATE_FLOOR = 0.5

# --- shared by every family that manipulates (issue 12, all manipulation rows) ---
PICK_DURATION: Range = (0.8, 1.5)  # s, picks and drops everywhere
DROP_DURATION: Range = (0.8, 1.5)  # s
BOX_SIDE: Range = (0.10, 0.25)  # m, each full extent of a box (transfer row; used by all)
NEAR_SIDE: Range = (0.20, 0.28)  # m, trunk axis to the object's near side at the pick
TABLE_TOP: Range = (0.40, 0.55)  # m, top of every table, platform and conveyor
# m: the table's near edge lies this far beyond the object's near side (the object overhangs
# the edge a little, as in the examples, so the hands can reach its sides).
TABLE_OVERHANG: Range = (0.0, 0.04)
FIXTURE_SIDE: Range = (0.30, 0.60)  # m, footprint side of a table, platform or conveyor
TARGET_NEAR_EDGE: Range = (0.15, 0.25)  # m, trunk axis to a drop target's near edge
# Gait of the manipulation families: period and swing (s); the swing is also kept <= P/2.
MANIP_PERIOD: Range = (0.35, 0.45)
MANIP_SWING: Range = (0.15, 0.20)
SETTLE = 1.0  # s, `end` is the last task's end plus this

# --- transfer: turn, pick during it, turn back, drop during that ---
TRANSFER_TURN1: Range = (30.0, 180.0)  # deg, magnitude of the first turn, either sign
TRANSFER_TURN2: Range = (60.0, 180.0)  # deg, magnitude of the turn back (opposite sign)
TRANSFER_TURN_RATE = 65.0  # deg/s, at most, loaded or not
TRANSFER_MASS: Range = (0.5, 6.0)  # kg
CONVEYOR_SPEED: Range = (0.0, 0.30)  # m/s, belt speed of a conveyor target

# --- walk-carry: pick from a table in front, turn, walk forward, place ahead ---
WALK_CARRY_TURN: Range = (0.0, 90.0)  # deg, magnitude, either sign
WALK_CARRY_TURN_RATE = 65.0  # deg/s (the loaded-turn limit of the transfer row)
WALK_CARRY_DISTANCE: Range = (0.3, 1.5)  # m, forward
WALK_CARRY_SPEED = 0.30  # m/s, at most
WALK_CARRY_MASS: Range = (0.5, 8.0)  # kg
# s, the turn starts this long before the pick's end (negative: after it); issue 12's
# "may start during the pick's last part", as in pick-walk-drop.yaml (0.2 s before).
WALK_CARRY_TURN_LEAD: Range = (-0.2, 0.3)
# s, the drop starts this long before the walk's end (negative: after it).
WALK_CARRY_DROP_LEAD: Range = (-0.3, 0.5)

# --- side-carry: pick from a table in front, side-step, place in front ---
SIDE_STEP: Range = (0.3, 0.6)  # m, magnitude, to the left or the right
SIDE_SPEED = 0.25  # m/s, at most
SIDE_MASS: Range = (0.5, 5.0)  # kg

# --- standing hold: pick, stand holding it, put it back on the same table ---
HOLD_MASS: Range = (0.5, 14.0)  # kg
HOLD_TIME: Range = (2.0, 6.0)  # s, the stand task between pick and drop

# --- locomotion: 2-4 walks, turns and steps ---
LOCO_TASKS = (2, 4)  # how many tasks, inclusive
LOCO_PERIOD: Range = (0.3, 0.5)  # s, gait period
LOCO_SWING_FRACTION: Range = (0.40, 0.50)  # swing time over the period
LOCO_WALK_DISTANCE: Range = (0.1, 1.5)  # m, in any direction
LOCO_WALK_SPEED = 0.35  # m/s, at most
LOCO_WALK_ANGLE: Range = (0.0, 60.0)  # deg, magnitude of a walk's turn (half the walks)
LOCO_TURN: Range = (10.0, 180.0)  # deg, magnitude
LOCO_TURN_RATE = 90.0  # deg/s, at most (also bounds a walk's `angle` rate)
LOCO_STEP: Range = (0.8, 3.0)  # s, stepping in place
LOCO_PAUSE: Range = (0.1, 1.0)  # s, between tasks when not back to back (half the gaps)

# --- throw: a sphere from a table in front, thrown forward ---
BALL_RADIUS: Range = (0.05, 0.10)  # m
THROW_MASS: Range = (0.3, 2.0)  # kg
THROW_VX: Range = (1.0, 2.0)  # m/s, body frame, forward
THROW_VY: Range = (-0.3, 0.3)  # m/s, sideways
THROW_VZ: Range = (0.5, 1.5)  # m/s, up
THROW_DURATION: Range = (0.8, 1.5)  # s (throw.yaml: 1.0)
THROW_DELAY: Range = (0.3, 1.0)  # s, from the pick's end to the throw's start
