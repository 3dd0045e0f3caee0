"""Named constants of the plan compiler: gait limits, manipulation phase fractions, hand poses.

Phase fractions are fractions of the task's duration, measured from its start. Poses marked
"in trunk" are relative to the trunk origin in the trunk's yaw-only frame (x forward, y left,
z up), in metres; the sign of y is flipped for the right hand.
"""

from __future__ import annotations

from typing import Final

# --- gait ------------------------------------------------------------------------------------
# Smallest double support kept after each swing when a short locomotion task squeezes the
# gait cycle (s).
GAIT_MIN_DOUBLE_SUPPORT: Final = 0.02

# --- pick ------------------------------------------------------------------------------------
# 0 .. PICK_REACH_END: reach from the current hand pose to the pre-grasp points (clearance
# outside the object's sides). PICK_REACH_END .. PICK_CONTACT: squeeze in to the sides; the hand
# contact (sigma_H) starts at PICK_CONTACT. PICK_CONTACT .. PICK_LIFTOFF: hold still while the
# grip builds. PICK_LIFTOFF: the object leaves its support (sigma_e starts).
# The squeeze gets 15% of the duration so that the hands meet the object slowly (about
# 0.4 m/s for a 1 s pick) instead of slamming into it.
# PICK_LIFTOFF .. PICK_RAISE_END: raise straight up by PICK_RAISE_HEIGHT (clean lift-off, no
# sliding on the support). PICK_RAISE_END .. 1: move to the carry pose in the trunk frame.
PICK_REACH_END: Final = 0.40
PICK_CONTACT: Final = 0.55
PICK_LIFTOFF: Final = 0.60
PICK_RAISE_END: Final = 0.75
PICK_RAISE_HEIGHT: Final = 0.04

# --- drop ------------------------------------------------------------------------------------
# 0 .. DROP_HOVER_END: carry pose -> DROP_HOVER_HEIGHT above the place pose.
# DROP_HOVER_END .. DROP_RELEASE: lower onto the support and settle; at DROP_RELEASE the hands
# let go (sigma_H and sigma_e end). DROP_RELEASE .. DROP_OPEN_END: open sideways to the grasp
# clearance (world frame, so the object is not dragged). DROP_OPEN_END .. 1: retract to the
# default pose in the trunk frame. The release comes at 75% rather than later so that the
# retract does not demand hand speeds above about 1.5 m/s for 0.8 s drops.
DROP_HOVER_END: Final = 0.60
DROP_RELEASE: Final = 0.75
DROP_OPEN_END: Final = 0.83
DROP_HOVER_HEIGHT: Final = 0.04
# Margin between the object's footprint and the edge of a fixture's top (m).
PLACE_MARGIN: Final = 0.02

# --- throw -----------------------------------------------------------------------------------
# 0 .. THROW_WINDUP_END: carry pose -> wind-up point, at rest. THROW_WINDUP_END .. THROW_RELEASE:
# accelerate along a straight line in the trunk frame from rest to the commanded velocity
# (profile 2 tau^3 - tau^4: zero acceleration at both ends, so the line is |v| T / 2 long);
# release at THROW_RELEASE. THROW_RELEASE .. THROW_FOLLOW_END: decelerate along the same line
# to rest (mirror profile). THROW_FOLLOW_END .. 1: return to the default pose (28% of the
# duration, so the return stays below about 1.5 m/s for 0.8 s throws).
THROW_WINDUP_END: Final = 0.45
THROW_RELEASE: Final = 0.65
THROW_FOLLOW_END: Final = 0.72
# The release point lies this far beyond the carry pose along the throw direction (m).
THROW_RELEASE_OFFSET: Final = 0.10

# --- hand poses ------------------------------------------------------------------------------
# Default (carry-ready) hand position of the LEFT hand in trunk (m); right hand mirrors y.
HAND_DEFAULT_IN_TRUNK: Final = (0.28, 0.12, -0.05)
# Carry pose of a held object's centre in trunk (m): ahead of and slightly below the origin.
CARRY_FORWARD: Final = 0.30
CARRY_HEIGHT: Final = 0.02
# Pre-grasp clearance outside the object's sides (m).
GRASP_CLEARANCE: Final = 0.03
# The contact targets lie this far inside the object's sides, so that the hands' Cartesian PD
# presses on the object (m).
GRASP_SQUEEZE: Final = 0.01

# Minimum horizontal distance below which an approach direction is taken from the planned
# heading instead of from the robot-to-object vector (m).
APPROACH_MIN_DISTANCE: Final = 1e-6
