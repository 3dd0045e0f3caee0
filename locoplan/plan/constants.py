"""Named constants of the plan compiler: gait limits, manipulation phase fractions, hand poses.

Phase fractions are fractions of the task's duration, measured from its start. Poses marked
"in trunk" are relative to the trunk origin in the trunk's yaw-only frame (x forward, y left,
z up), in metres; the sign of y is flipped for the right hand.
"""

from __future__ import annotations

import math
from typing import Final

# --- gait ------------------------------------------------------------------------------------
# Smallest double support kept after each swing when a short locomotion task squeezes the
# gait cycle (s).
GAIT_MIN_DOUBLE_SUPPORT: Final = 0.02

# --- pick ------------------------------------------------------------------------------------
# 0 .. PICK_REACH_END: reach from the current hand pose to the pre-grasp points (clearance
# outside the object's sides; see locoplan.plan.manipulation for the tucked approach, which may
# start before the pick when the hands would otherwise sweep into the object or its support).
# PICK_REACH_END .. PICK_CONTACT: close in until the hand spheres touch the sides, decelerating
# to rest there (no impact). PICK_CONTACT .. PICK_LIFTOFF: press GRASP_SQUEEZE into the sides;
# the hand contact (sigma_H) starts at PICK_CONTACT. PICK_LIFTOFF: the object leaves its support
# (sigma_e starts). PICK_LIFTOFF .. PICK_RAISE_END: raise straight up by PICK_RAISE_HEIGHT.
# PICK_RAISE_END .. 1: to the carry pose in the trunk frame, which is up (to CARRY_HEIGHT) rather
# than in: the hands take the weight only as the controller's load feedforward ramps in, and
# the object must not be dragged over its support while it may still rest on it.
PICK_REACH_END: Final = 0.40
PICK_CONTACT: Final = 0.55
PICK_LIFTOFF: Final = 0.60
PICK_RAISE_END: Final = 0.75
PICK_RAISE_HEIGHT: Final = 0.04

# --- drop ------------------------------------------------------------------------------------
# 0 .. DROP_HOVER_END: carry pose -> DROP_HOVER_HEIGHT above the place pose.
# DROP_HOVER_END .. DROP_RELEASE: lower onto the support and settle; at DROP_RELEASE the hands
# let go (sigma_H and sigma_e end). DROP_RELEASE .. DROP_OPEN_END: open sideways beyond the
# grasp clearance (world frame, so the object is not dragged; wider on the side a conveyor
# carries the object to). DROP_OPEN_END .. 1: retreat to the tucked pose in the trunk frame,
# first back along the object's sides (DROP_BACK_SHARE of that time) when a straight retreat
# would pass too close to it.
DROP_HOVER_END: Final = 0.55
DROP_RELEASE: Final = 0.70
DROP_OPEN_END: Final = 0.78
DROP_BACK_SHARE: Final = 0.4
DROP_HOVER_HEIGHT: Final = 0.04
# Margin between the object's footprint and the edge of a fixture's top (m).
PLACE_MARGIN: Final = 0.02

# --- throw -----------------------------------------------------------------------------------
# 0 .. THROW_WINDUP_END: carry pose -> wind-up point, at rest. THROW_WINDUP_END ..
# THROW_ACCELERATE_END: accelerate along a straight line (world, laid out from the planned trunk
# pose at the release) from rest to the throw velocity (profile 2 tau^3 - tau^4: the stretch is
# |v| T / 2 long). THROW_ACCELERATE_END .. THROW_RELEASE: cruise at that velocity while the
# squeeze eases off; release at THROW_RELEASE. THROW_RELEASE .. THROW_FOLLOW_END: decelerate
# along the same line to rest while the hands open. THROW_FOLLOW_END .. 1: return to the
# default pose.
THROW_WINDUP_END: Final = 0.40
THROW_ACCELERATE_END: Final = 0.61
THROW_RELEASE: Final = 0.63
THROW_FOLLOW_END: Final = 0.72
# The follow-through ends this far beyond the carry pose along the throw direction (m): the
# whole line then runs from about 0.15 m behind the carry pose (the object clear of the
# trunk's front) to 0.16 m ahead of it (the hands 0.44 m from the shoulders).
THROW_STOP_OFFSET: Final = 0.16
# Speed of the planned push relative to the commanded release speed.
THROW_SPEED_GAIN: Final = 1.0

# --- hand poses ------------------------------------------------------------------------------
# Default (carry-ready) hand position of the LEFT hand in trunk (m); right hand mirrors y.
HAND_DEFAULT_IN_TRUNK: Final = (0.28, 0.12, -0.05)
# Carry pose of a held object's centre in trunk (m): ahead of and slightly below the origin.
CARRY_FORWARD: Final = 0.30
# A picked object is carried where it was picked within this distance of CARRY_FORWARD (m).
CARRY_FORWARD_RANGE: Final = 0.06
CARRY_HEIGHT: Final = 0.02
# Pre-grasp clearance outside the object's sides (m): from the hand point, so the hand sphere
# (HAND_RADIUS) keeps 3 cm, more than the hands' tracking error (about 2 cm).
GRASP_CLEARANCE: Final = 0.05
# Boxes carried through a walk or turn are gripped this far above their centre (m), but at
# least HAND_RADIUS + GRASP_TOP_MARGIN below their top: two point contacts leave a box free to
# turn about the line through them, and a grip above the centre of mass makes it hang level
# (locoplan.plan.manipulation.grip_height).
GRASP_ABOVE_CENTRE: Final = 0.04
GRASP_TOP_MARGIN: Final = 0.01
# The contact targets lie this far inside the object's sides, so that the hands' Cartesian PD
# presses on the object (m).
GRASP_SQUEEZE: Final = 0.01

# Minimum horizontal distance below which an approach direction is taken from the planned
# heading instead of from the robot-to-object vector (m).
APPROACH_MIN_DISTANCE: Final = 1e-6

# --- hand clearance (locoplan.plan.clearance) ------------------------------------------------
# Radius of the hand collision spheres (m); robots/hector/hector.xml, geoms *_hand_sphere.
HAND_RADIUS: Final = 0.02
# Smallest gap (m) kept between a hand sphere and any object or fixture while the hands move
# towards or away from an object: the hands track their targets within about 2 cm.
APPROACH_CLEARANCE: Final = 0.025
# A hand that starts closer than that (resting beside an object) may come this much closer (m).
APPROACH_SLACK: Final = 0.005
# How far the trunk's yaw may be off the plan when hand paths are checked: YAW_LAG_TIME (s)
# times the planned yaw rate (the trunk lags about 4 deg at 1.8 rad/s in a loaded turn), and at
# least YAW_ERROR_MIN (rad).
YAW_LAG_TIME: Final = 0.04
YAW_ERROR_MIN: Final = math.radians(0.5)
# Sampling period of the clearance check (s).
CLEARANCE_DT: Final = 0.01
# Tucked hand pose of the LEFT hand in trunk (m): close to the body and wide, so that the hands
# stay clear of what the robot turns or walks towards (within 0.2 m of the trunk
# axis, inside a table's near edge 0.25 m away).
HAND_TUCK_IN_TRUNK: Final = (0.10, 0.17, -0.05)
# Time to move a hand into the tucked pose (s), and how long before the first predicted
# collision of the direct path the tuck is complete (s).
TUCK_DURATION: Final = 0.4
TUCK_LEAD: Final = 0.1
# Shortest reach from the tucked pose to the pre-grasp points (s): about 0.25 m at a peak speed
# below 1.9 m/s.
REACH_MIN_DURATION: Final = 0.25
# Step of the search for the earliest collision-free reach start (s).
REACH_START_STEP: Final = 0.02
