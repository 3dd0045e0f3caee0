"""The robot's figures the planner needs, as one value: `PlanGeometry`.

The plan compiler reads no robot files and builds no MuJoCo or pinocchio model for it: whoever
plans for a robot builds a `PlanGeometry` from its loaded `RobotDescription` (`plan_geometry`:
robot.yaml's nominal trunk height, stance width, foot, hand radius and `planner` section) and
passes it in (`locoplan.sim.robot_plan.compile_robot_plan`; the scenario loader for its
feasibility checks). The defaults are HECTOR's figures, the values `locoplan.plan.constants`
has always had, so `compile_plan(scenario)` plans for HECTOR exactly as before.

Poses "in trunk" are relative to the trunk origin (the free-flyer body's origin: HECTOR's
trunk, H1's pelvis) in its yaw-only frame (x forward, y left, z up), for the LEFT hand; the
right hand mirrors y.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from locoplan.plan import constants as k

if TYPE_CHECKING:
    from locoplan.robot.description import RobotDescription

Vec3 = tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class PlanGeometry:
    """Robot figures of the plan (m, rad).

    `base_height`: trunk origin above the soles in the reference; `foot_width`: lateral
    distance of the planned footholds. `hand_default_in_trunk`: where the hands rest and start
    (carry-ready); `hand_tuck_in_trunk`: the tucked pose, close to the body and below the
    tables (constants' HAND_TUCK_IN_TRUNK says what it must clear); `hand_radius`: the hand
    contact sphere's radius; `grasp_tolerance`: how near a hand point must come to an
    object's surface for the hand to close (the simulator's grasp and the plan's reach checks
    share it: the sphere touches at `hand_radius`, so it closes 1 cm beyond touching);
    `grasp_clearance`: the hand point's distance outside an object's side before and after
    the grasp (the sphere keeps 3 cm, more than the hands' tracking error).
    `carry_forward`: how far ahead of the trunk origin a held object's centre is carried;
    `throw_stop_offset`: how far beyond the carry pose a throw's follow-through ends;
    `trunk_front`: the trunk's front face ahead of its origin (what a carried object is
    pulled in towards). `walk_stride`: how far (m) a foot in stance may move ahead of or
    behind its hip in a gait period (the feasibility check's walk-speed bound);
    `hip_yaw_range`: the hip yaw joint's range either side of straight ahead (its turn-rate
    bound); `footprint_radius`: the radius around the start position that the feet occupy
    (an object there overlaps the robot). `hand_accel_limit` (m/s^2), `arm_moving_mass`
    (kg), `tuck_lift_duration` (s): the arms' free-move acceleration, their moving mass and
    the tucked hand's rise (constants' HAND_ACCEL_LIMIT, ARM_MOVING_MASS,
    TUCK_LIFT_DURATION)."""

    base_height: float = 0.60
    foot_width: float = 0.2
    hand_default_in_trunk: Vec3 = k.HAND_DEFAULT_IN_TRUNK
    hand_tuck_in_trunk: Vec3 = k.HAND_TUCK_IN_TRUNK
    hand_radius: float = k.HAND_RADIUS
    grasp_tolerance: float = k.GRASP_TOLERANCE
    grasp_clearance: float = k.GRASP_CLEARANCE
    carry_forward: float = k.CARRY_FORWARD
    throw_stop_offset: float = k.THROW_STOP_OFFSET
    trunk_front: float = k.TRUNK_FRONT
    walk_stride: float = k.WALK_STRIDE
    hip_yaw_range: float = k.HIP_YAW_RANGE
    footprint_radius: float = k.ROBOT_FOOTPRINT_RADIUS
    hand_accel_limit: float = k.HAND_ACCEL_LIMIT
    arm_moving_mass: float = k.ARM_MOVING_MASS
    tuck_lift_duration: float = k.TUCK_LIFT_DURATION

    @property
    def settle_time(self) -> float:
        """The trunk's pendulum time sqrt(base_height / g) (s): how long the robot shifts
        its weight before its first lift-off (`gait.start_lead`); HECTOR 0.247 s, H1 0.33 s."""
        return math.sqrt(self.base_height / 9.81)

    def __post_init__(self) -> None:
        for name in (
            "base_height",
            "foot_width",
            "hand_radius",
            "grasp_tolerance",
            "grasp_clearance",
            "carry_forward",
            "trunk_front",
            "walk_stride",
            "hip_yaw_range",
            "footprint_radius",
            "hand_accel_limit",
            "arm_moving_mass",
            "tuck_lift_duration",
        ):
            value = getattr(self, name)
            if not (value > 0.0 and math.isfinite(value)):
                raise ValueError(f"{name} must be positive and finite, got {value}")
        if not (self.throw_stop_offset >= 0.0 and math.isfinite(self.throw_stop_offset)):
            raise ValueError(f"throw_stop_offset must be >= 0, got {self.throw_stop_offset}")
        for name in ("hand_default_in_trunk", "hand_tuck_in_trunk"):
            pose = getattr(self, name)
            if len(pose) != 3 or not all(math.isfinite(v) for v in pose) or pose[1] <= 0.0:
                raise ValueError(f"{name} must be 3 finite numbers with y > 0 (left), got {pose}")


HECTOR_GEOMETRY = PlanGeometry()

# How far (m) beyond touching its object a hand closes (GRASP_TOLERANCE - HAND_RADIUS for
# HECTOR: the hand point 1 cm outside the sphere's touching distance). With H1's 0.033 m hand
# sphere a fixed 0.03 m would ask the hand point to come 3 mm inside its sphere's touching
# distance, into the box (not tried in closed loop). Checked on H1's standing holds only
# (scenarios/h1-standing-hold.yaml and 10 envelope holds of 2.8-8.6 kg, seed 31: all closed
# and placed); HECTOR's value is unchanged.
GRASP_BEYOND_TOUCH = 0.01
# The gap (m) the hand sphere keeps from an object's side before and after the grasp
# (GRASP_CLEARANCE - HAND_RADIUS for HECTOR: 3 cm, more than the hands' 2 cm tracking error);
# checked on the same H1 holds.
GRASP_SPHERE_GAP = 0.03


def plan_geometry(desc: RobotDescription) -> PlanGeometry:
    """The plan's figures of the robot `desc`: trunk height (robot.yaml
    `nominal.trunk_height`), foothold spacing (`stance_width`), hand radius
    (`contacts.hand_radius`), the grasp tolerance 1 cm beyond it (GRASP_BEYOND_TOUCH) and
    the pre-grasp clearance 3 cm beyond it (GRASP_SPHERE_GAP),
    the `planner` section's hand poses, carry, throw, trunk front, gait limits and arm
    figures, and the
    feet's footprint radius around the start position, hypot(foot.toe, stance_width / 2)
    (the toe of a foot half the stance width off the centre line). For HECTOR's description
    every figure equals HECTOR_GEOMETRY's."""
    p = desc.planner
    return PlanGeometry(
        base_height=desc.base_height_nominal,
        foot_width=desc.stance_width,
        hand_default_in_trunk=p.hand_default,
        hand_tuck_in_trunk=p.hand_tuck,
        hand_radius=desc.hand_radius,
        grasp_tolerance=desc.hand_radius + GRASP_BEYOND_TOUCH,
        grasp_clearance=desc.hand_radius + GRASP_SPHERE_GAP,
        carry_forward=p.carry_forward,
        throw_stop_offset=p.throw_stop_offset,
        trunk_front=p.trunk_front,
        walk_stride=p.walk_stride,
        hip_yaw_range=p.hip_yaw_range,
        footprint_radius=math.hypot(desc.foot_toe, desc.stance_width / 2.0),
        hand_accel_limit=p.hand_accel_limit,
        arm_moving_mass=p.arm_moving_mass,
        tuck_lift_duration=p.tuck_lift_duration,
    )
