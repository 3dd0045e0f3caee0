"""The envelope the generator draws from: issue 12's table, one constant per range (HECTOR's),
and `envelope_ranges(robot)`, the ranges that depend on the robot at another robot's scale.

Every range here is inclusive and drawn uniformly on a grid (times 0.01 s, lengths 1 mm,
angles 0.1 deg, masses 0.01 kg). Where issue 12 gives only an upper bound on a rate ("at up
to 65 deg/s"), the rate is drawn from [RATE_FLOOR x max, max]: slower tasks are easier and
the paper's timings sit in that band (package-transfer turns at 56 deg/s, pick-walk-drop
walks at 0.25 m/s). A task's duration is its angle or distance over the drawn rate, rounded
up to 0.01 s (so the rate never exceeds the maximum), and never shorter than one gait period.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

from locoplan.envelope.geometry import ROBOT_RADIUS
from locoplan.plan.constants import HAND_RADIUS, HIP_YAW_RANGE, WALK_STRIDE

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
# m, per side: the platform stands at least the hand's width plus this twice over from the
# box's side, so that the hand waits between them before the grasp (the planner refuses less
# than twice PREGRASP_GAP: `hand_paths.pregrasp_offset`; the rest is margin).
HAND_ROOM_MARGIN = 0.01


def side_carry_hand_room(hand_radius: float) -> float:
    """The least gap (m) between a side-carry's box and the platform beside it for a hand of
    `hand_radius` (m): the hand's width and HAND_ROOM_MARGIN on each side of it."""
    return round(2.0 * (hand_radius + HAND_ROOM_MARGIN), 3)


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


# --- per robot ---------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class EnvelopeRanges:
    """The ranges that depend on the robot, for one robot (`envelope_ranges`); the defaults
    are HECTOR's, the constants above, which the issue's table was written for.

    `robot`: the robot's name, written into each script unless it is the format's default
    robot; heights and distances (m): `table_top`, `near_side`, `target_near_edge`,
    `robot_radius` (the disc around the trunk axis nothing may come nearer to, on the
    robot's path: `locoplan.envelope.geometry.ROBOT_RADIUS` for HECTOR); masses (kg):
    `transfer_mass`, `walk_carry_mass`, `side_mass`, `hold_mass`, `throw_mass`; gait
    limits: `walk_stride` (m) and `hip_yaw_range` (rad), those of the feasibility check
    (`locoplan.scenario.feasibility`) that durations are stretched to meet; `hand_room` (m):
    the least gap between a side-carry's box and the platform beside it (the hand's width
    and HAND_ROOM_MARGIN on each side of it)."""

    robot: str = "hector"
    table_top: Range = TABLE_TOP
    near_side: Range = NEAR_SIDE
    target_near_edge: Range = TARGET_NEAR_EDGE
    robot_radius: float = ROBOT_RADIUS
    transfer_mass: Range = TRANSFER_MASS
    walk_carry_mass: Range = WALK_CARRY_MASS
    side_mass: Range = SIDE_MASS
    hold_mass: Range = HOLD_MASS
    throw_mass: Range = THROW_MASS
    walk_stride: float = WALK_STRIDE
    hip_yaw_range: float = HIP_YAW_RANGE
    hand_room: float = side_carry_hand_room(HAND_RADIUS)


HECTOR_RANGES = EnvelopeRanges()

# The robot the table was written for: another robot's ranges are HECTOR's moved and
# scaled by how it differs from HECTOR (`envelope_ranges`).
REFERENCE_ROBOT = "hector"


def envelope_ranges(robot: str = REFERENCE_ROBOT) -> EnvelopeRanges:
    """The envelope for `robot` (a name under robots/ or a robot.yaml path): HECTOR's ranges
    moved to the robot's scale, from its description (`locoplan.plan.robot_geometry.
    plan_geometry`) and its static analysis (`locoplan.plan.statics`). For HECTOR every
    shift below is 0 and every ratio 1, so its ranges are the constants above exactly.

    - heights (TABLE_TOP): shifted by how much higher the robot's default hands stand above
      the soles (trunk height + the default hand pose's z) than HECTOR's (0.55 m): the
      tables keep their height relative to where the hands rest (H1: +0.522 m, tops
      0.922-1.072 m; its tuck, 0.870 m at the sphere's top, stays below them);
    - distances from the trunk axis (NEAR_SIDE, TARGET_NEAR_EDGE, ROBOT_RADIUS): shifted by
      how much farther the robot's feet reach from the start position (the feasibility
      check's footprint radius, hypot(toe, stance / 2)) than HECTOR's (0.135 m): objects and
      targets keep HECTOR's margin outside the feet (H1: +0.112 m, objects' near side
      0.312-0.392 m);
    - masses (every family's): the upper bound scaled by the payload the robot holds
      statically at its carry pose (CARRY_FORWARD ahead at CARRY_HEIGHT, the hands at the
      default pose's width) over HECTOR's (20.7 kg at its hip pitch; H1: 13.0 kg at its
      elbows, ratio 0.63: standing holds up to 8.8 kg); the lower bound stays;
    - gait limits: the robot's walk stride and hip yaw range (robot.yaml `planner`).

    Durations, rates, turn angles, walk distances, box and fixture sizes, throw velocities
    are the table's for every robot (the rates are bounded by the robot's gait limits
    anyway). Computed once per robot per process (the static analysis takes about 0.1 s)."""
    return _envelope_ranges(robot)


@functools.cache
def _envelope_ranges(robot: str) -> EnvelopeRanges:
    from locoplan.plan.robot_geometry import plan_geometry
    from locoplan.robot.description import load_robot_description

    geo = plan_geometry(load_robot_description(robot))
    ref = plan_geometry(load_robot_description(REFERENCE_ROBOT))
    lift = (geo.base_height + geo.hand_default_in_trunk[2]) - (
        ref.base_height + ref.hand_default_in_trunk[2]
    )
    out = geo.footprint_radius - ref.footprint_radius
    ratio = carry_payload_limit(robot) / carry_payload_limit(REFERENCE_ROBOT)

    def shifted(r: Range, by: float) -> Range:
        return (round(r[0] + by, 3), round(r[1] + by, 3))

    def scaled(r: Range) -> Range:
        return (r[0], max(r[0], math.floor(r[1] * ratio * 100.0 + 1e-9) / 100.0))

    return EnvelopeRanges(
        robot=robot,
        table_top=shifted(TABLE_TOP, lift),
        near_side=shifted(NEAR_SIDE, out),
        target_near_edge=shifted(TARGET_NEAR_EDGE, out),
        robot_radius=round(ROBOT_RADIUS + out, 3),
        transfer_mass=scaled(TRANSFER_MASS),
        walk_carry_mass=scaled(WALK_CARRY_MASS),
        side_mass=scaled(SIDE_MASS),
        hold_mass=scaled(HOLD_MASS),
        throw_mass=scaled(THROW_MASS),
        walk_stride=geo.walk_stride,
        hip_yaw_range=geo.hip_yaw_range,
        hand_room=side_carry_hand_room(geo.hand_radius),
    )


def carry_payload_limit(robot: str) -> float:
    """The mass (kg) `robot` holds statically, standing, with its hands CARRY_FORWARD ahead
    of the trunk origin at CARRY_HEIGHT and as wide apart as its default hand pose, its
    pelvis shifted to balance (`locoplan.plan.statics.StaticModel.analyse`)."""
    from locoplan.plan.constants import CARRY_HEIGHT
    from locoplan.plan.robot_geometry import plan_geometry
    from locoplan.plan.statics import HeldPose, static_model
    from locoplan.robot.description import load_robot_description

    geo = plan_geometry(load_robot_description(robot))
    y = geo.hand_default_in_trunk[1]
    hands = ((geo.carry_forward, y, CARRY_HEIGHT), (geo.carry_forward, -y, CARRY_HEIGHT))
    pose = HeldPose(geo.base_height, (0, 1), hands)
    return float(static_model(robot).analyse(pose, 0.0).payload_limit)
