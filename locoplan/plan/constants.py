"""Named constants of the plan compiler: gait limits, manipulation phase fractions, hand poses.

Phase fractions are fractions of the task's duration, measured from its start. Poses marked
"in trunk" are relative to the trunk origin in the trunk's yaw-only frame (x forward, y left,
z up), in metres; the sign of y is flipped for the right hand.

Robot figures (the hand poses, HAND_RADIUS, GRASP_TOLERANCE, CARRY_FORWARD,
THROW_STOP_OFFSET, TRUNK_FRONT, WALK_STRIDE, HIP_YAW_RANGE, ROBOT_FOOTPRINT_RADIUS) are
HECTOR's: they are the defaults of `locoplan.plan.robot_geometry.PlanGeometry`, which is what
the planner reads; another robot states its own in its robot.yaml (`planner:`; see
docs/robots.md). The phase fractions, accelerations and clearances were tuned and checked on
HECTOR only (the scripts and envelope seeds each comment names); they are the same for every
robot until a robot's closed loop says otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

# --- gait ------------------------------------------------------------------------------------
# Smallest double support kept after each swing when a short locomotion task squeezes the
# gait cycle (s).
GAIT_MIN_DOUBLE_SUPPORT: Final = 0.02
# HECTOR's gait limits (`locoplan.scenario.feasibility`'s docstring derives them; robot.yaml
# `planner.walk_stride` / `planner.hip_yaw_range_deg` for another robot). Half the kinematic
# stride of the leg (m): thigh + calf 0.44 m, hip 0.40 m above the sole at the nominal 0.60 m
# trunk height, sqrt(0.44^2 - 0.40^2) = 0.18 m ahead of or behind the hip.
WALK_STRIDE: Final = 0.18
# Hip yaw range (rad) either side of straight ahead (shared/robot.md).
HIP_YAW_RANGE: Final = math.radians(30.0)
# Radius (m) around the start position that HECTOR's feet occupy: the toe sphere 0.09 m ahead
# of the ankle on a foot 0.1 m off the centre line, hypot(0.09, 0.10); for any robot
# hypot(foot.toe, stance_width / 2) (`locoplan.sim.robot_plan.plan_geometry`).
ROBOT_FOOTPRINT_RADIUS: Final = math.hypot(0.09, 0.10)


# --- pick ------------------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class PickPhases:
    """When a pick's phases end, as fractions of its duration, and how high it raises (m).

    0 .. reach_end: reach from the current hand pose to the pre-grasp points (clearance outside
    the object's sides; see locoplan.plan.manipulation for the tucked approach, which may start
    before the pick when the hands would otherwise sweep into the object or its support).
    reach_end .. contact: close in until the hand spheres touch the sides, decelerating to rest
    there (no impact). contact .. liftoff: press GRASP_SQUEEZE into the sides; the hand contact
    (sigma_H) starts at contact. liftoff: the object leaves its support (sigma_e starts).
    liftoff .. raise_end: straight up by raise_height, world frame. raise_end .. 1: to the carry
    pose in the trunk frame, which is up (to CARRY_HEIGHT) rather than in (see
    locoplan.plan.manipulation.carry_forward).
    """

    reach_end: float
    contact: float
    liftoff: float
    raise_end: float
    raise_height: float


# A pick whose object is then held standing still (the 14 kg hold of standing-load.yaml is tuned
# on these: its margins are thin).
PICK_STANDING: Final = PickPhases(0.40, 0.55, 0.60, 0.75, 0.04)
# A pick whose object is carried through a walk, turn or steps: grasp and lift earlier and raise
# longer and higher, straight up. The controller's load feedforward ramps in over 0.8 s after
# the lift-off, so the object only leaves its support about 0.4 s later; it must be clear of it
# (and not dragged across it) before the robot turns or walks with it. Measured on
# package-transfer.yaml over package masses 2.6-3.4 kg: 12 of 14 runs placed the package
# without a fall with these phases, 5 of 14 with PICK_STANDING's.
PICK_CARRIED: Final = PickPhases(0.35, 0.45, 0.50, 0.85, 0.06)
# A pick gripped behind its object's centre (GRIP_BEHIND_CENTRE) that pulls it in during the
# raise (`manipulation`, `pull`) goes straight up for this share of the raise and pulls in
# over the rest. Why: the object leaves its support only once the hands carry its weight,
# 0.09-0.18 s after the planned lift-off for 5-8 kg boxes (raises of 0.29-0.52 s); pulled in
# before then it is dragged across its table, and the friction's reaction at the hands draws
# the robot towards the table (envelope seed 62021, walk-carry-010: 146 N at the hands, the
# trunk 18 cm forward; straight up first: under 15 N once the box had left). Only 0.5 was
# tried (on the 52 runs that failed on seeds 53021-58021 and 62021, and seeds 63021, 64021).
RAISE_UP_SHARE: Final = 0.5

# --- drop ------------------------------------------------------------------------------------
# 0 .. DROP_HOVER_END: carry pose -> DROP_HOVER_HEIGHT above the place pose (moving with the
# trunk). DROP_HOVER_END .. DROP_RELEASE: lower onto the support (world); at DROP_RELEASE the
# hands let go (sigma_H and sigma_e end). DROP_RELEASE .. DROP_OPEN_END: open sideways beyond
# the grasp clearance (world frame, so the object is not dragged; wider on the side a conveyor
# carries the object to). DROP_OPEN_END .. 1: retreat to the tucked pose in the trunk frame,
# first back along the object's sides (DROP_BACK_SHARE of that time) when a straight retreat
# would pass too close to it. The retreat gets a third of the drop: about 0.2 m, which in a 1 s
# drop keeps the hands below 1.2 m/s (faster retreats shook the robot off balance after the
# release). HOVER_END and RELEASE are where those phases end when the lowering has room; one
# that would accelerate its load faster than `hand_paths.pull_accel` allows takes its time
# from the hover and then from after RELEASE, up to the drop's end
# (`manipulation._Builder._drop_times`).
DROP_HOVER_END: Final = 0.45
DROP_RELEASE: Final = 0.60
DROP_OPEN_END: Final = 0.68
DROP_BACK_SHARE: Final = 0.4
DROP_HOVER_HEIGHT: Final = 0.04
# The lowering ends this far (m) below where the object rests on its support, so that it is
# set down by the release: the hands sag 1-2 cm under a 5-10 kg load and the trunk sinks, and a
# lowering aimed at the resting height left a 10 kg block 0.5-1 cm up at the release, whose
# whole weight then left the hands at once while the robot still leaned back against it (it
# fell backwards: envelope seed 4711, standing-hold-022). The controller's guarded lowering
# (`locoplan.control.controller`, SUPPORTED_LOAD) stops the hands once the support carries
# the object, so the press does not push it down.
DROP_PRESS: Final = 0.02
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
# HECTOR's (`PlanGeometry.throw_stop_offset`; robot.yaml `planner.throw_stop_offset`). The
# follow-through ends this far beyond the carry pose along the throw direction (m): the
# whole line then runs from about 0.15 m behind the carry pose (the object clear of the
# trunk's front) to 0.16 m ahead of it (the hands 0.44 m from the shoulders).
THROW_STOP_OFFSET: Final = 0.16
# Smallest gap (m) kept between a thrown object pushed along the throw line and any fixture or
# object (the line is raised as much as that needs; the hands track within about 2 cm).
THROW_CLEARANCE: Final = 0.04
# Speed of the planned push relative to the commanded release speed.
THROW_SPEED_GAIN: Final = 1.0

# --- hand poses ------------------------------------------------------------------------------
# HECTOR's default (carry-ready) hand position of the LEFT hand in trunk (m); right hand
# mirrors y: within 6 mm of where its keyframe puts the hands (0.274, 0.12, -0.051), so the
# arms start at rest (`PlanGeometry.hand_default_in_trunk`; robot.yaml `planner.hand_default`).
HAND_DEFAULT_IN_TRUNK: Final = (0.28, 0.12, -0.05)
# HECTOR's carry pose of a held object's centre in trunk (m): ahead of and slightly below the
# origin (`PlanGeometry.carry_forward`; robot.yaml `planner.carry_forward`).
CARRY_FORWARD: Final = 0.30
# A picked object is carried where it was picked within this distance of CARRY_FORWARD (m),
# then brought in to CARRY_FORWARD while the hands are free (at least CARRY_SETTLE_MIN, s),
# no faster than a rest-to-rest move peaking at CARRY_SETTLE_ACCEL (m/s^2), which tilts a
# hanging box by under 3 deg (at least CARRY_SETTLE_TIME, s).
CARRY_FORWARD_RANGE: Final = 0.06
CARRY_SETTLE_TIME: Final = 0.8
CARRY_SETTLE_MIN: Final = 0.3
CARRY_SETTLE_ACCEL: Final = 0.45
CARRY_HEIGHT: Final = 0.02
# An object carried through a walk, turn or steps comes in during the pick's raise until its
# near face is CARRY_IN_GAP (m) from the trunk's front, TRUNK_FRONT (m) ahead of the trunk
# origin (robots/hector/hector.xml: `trunk_box`'s half length), and stays there (no settle
# out to CARRY_FORWARD; TRUNK_FRONT is HECTOR's, `PlanGeometry.trunk_front`, robot.yaml
# `planner.trunk_front`). Why: in single support one hip pitch carries the whole upper body and
# the load; with the object's centre 0.30 m ahead the static single-support hip-pitch ratio
# (pinocchio, 6-D sole wrench) is 0.77 at 7 kg and 0.87 at 8 kg, against 0.37 / 0.42 standing
# on both feet, and the walk-carries of 5.4-7.8 kg saturated it in the first step after the
# pick and fell (envelope seed 8080: 13 of 15 falls); at 0.20 m it is 0.54 / 0.60, and the
# load's yaw inertia about the trunk axis drops by half. The gap covers the hands' tracking
# error under load (2-3 cm, as TRUNK_POSITION_ERROR). Checked on envelope seed 8080's 30
# walk-carries (0.5-8 kg, boxes 0.10-0.25 m: 24 succeeded against 14 carried at 0.30 m) and
# its 60 transfers and 20 side-carries (47 and 17 against 45 and 17).
TRUNK_FRONT: Final = 0.07
CARRY_IN_GAP: Final = 0.03
# A held object is carried with its bottom at least this far (m) above the top of every
# fixture it can sweep over while held (see `manipulation._Builder.swept_top`): 2 cm of
# clearance plus the 2 cm by which the trunk and hands sag under a carried 4-6 kg box
# (measured in the transfer family's closed loops, envelope seed 5). Heavier loads add
# CARRY_SAG_PER_KG (m/kg) of sag per kg beyond CARRY_SAG_FROM (kg): the sag is the trunk's
# height and the hands' tracking yielding to the load, linear in it (0.4 cm/kg fits both
# 2 cm at 5 kg and the 2.8 cm measured under 7.1 kg on envelope seed 26457, walk-carry-025,
# whose box, carried 4 cm above the platform's top as planned, hit that platform's edge and
# stopped the walk 12 cm short). `manipulation.carry_clearance` gives the sum.
CARRY_CLEARANCE: Final = 0.04
CARRY_SAG_PER_KG: Final = 0.004
CARRY_SAG_FROM: Final = 5.0
# How near (m) to a fixture it sweeps over a carried object may come, held where the arms
# stop short of an out-of-reach carry pose, before it is gripped at its centre
# (`payload.centre_grips`): the spread of the sag that the arms' shortfall predicts (HECTOR,
# envelope seed 54021: 3.0-4.5 cm measured against 4.5-5.4 cm predicted, about 1 cm less).
# Checked on seeds 53021-55021 (the objects so predicted 1.7-3.5 cm clear fared worse
# gripped at their centre, those predicted 1.3 cm in to 0.2 cm clear better) and then on
# 51021 and 52021 (README, Envelope).
CENTRE_GRIP_CLEARANCE: Final = 0.01
# How far (m) the arms may fall short of a drop's hover pose before the hover ends later
# (`payload.reachable_hovers`): an object held where the hands stop rides up to that much
# lower (the carry's measured sag, above), and the hover keeps it DROP_HOVER_HEIGHT over the
# target's top; so it still clears the top by CENTRE_GRIP_CLEARANCE.
HOVER_REACH_SLACK: Final = DROP_HOVER_HEIGHT - CENTRE_GRIP_CLEARANCE
# The time grid (s) on which `payload.reachable_hovers` looks for a reachable hover.
HOVER_SEARCH_STEP: Final = 0.02
# Trunk-path sampling step (s) when looking for the fixtures a held object sweeps over.
SWEEP_SAMPLE: Final = 0.05
# HECTOR's pre-grasp clearance outside the object's sides (m; `PlanGeometry.grasp_clearance`: the
# robot's hand radius + 3 cm): from the hand point, so the hand sphere
# (HAND_RADIUS) keeps 3 cm, more than the hands' tracking error (about 2 cm).
GRASP_CLEARANCE: Final = 0.05
# Boxes carried through a walk, turn or steps are gripped this far above their centre (m), but at
# least HAND_RADIUS + GRASP_TOP_MARGIN below their top: two point contacts leave a box free to
# turn about the line through them, and a grip above the centre of mass makes it hang level
# (locoplan.plan.manipulation.grip_height).
GRASP_ABOVE_CENTRE: Final = 0.04
GRASP_TOP_MARGIN: Final = 0.01
# A box whose grasp leaves the arms too little room for its lift's lean
# (`payload.behind_grips`) is gripped this far nearer the robot than its centre (m, along the
# approach), but with the hand points at least HAND_RADIUS + GRASP_TOP_MARGIN inside its near
# face (`hand_paths.grip_behind`); its centre rides that far ahead of the hands
# (`Plan.object_positions`) and is set down on the drop's target. 3 cm gives the arms that
# much room at the grasp. The box then hangs with its weight's moment m g d about the grip
# line, which the palms hold by friction up to (4/3) m g r_palm (`locoplan.sim.grasp`,
# r_palm 0.04 m: a 5.3 cm lever): 3 cm uses 56 % of it and leaves the rest for the swing of
# turns and steps (why only those boxes: `payload.behind_grips`). Only 3 cm was tried, with
# RAISE_UP_SHARE (figures in the CHANGELOG; 5-8 kg boxes 0.10-0.24 m deep).
GRIP_BEHIND_CENTRE: Final = 0.03
# The contact targets lie this far inside the object's sides, so that the hands' Cartesian PD
# presses on the object (m).
GRASP_SQUEEZE: Final = 0.01
# The least gap (m) the hand sphere keeps, where it waits beside an object before closing on
# it, from the object's side and from anything else (`hand_paths.pregrasp_offset`): a
# fixture nearer than that to every pre-grasp point between them leaves no room for the hand
# and the pick is refused (`ManipulationPlan.pick`). Measured on side-carry scripts whose
# platform stands beside the box (seeds 21-69021 on HECTOR, 21-59021 on H1; the pre-grasp
# point between box and platform, entry paths as in `approach_segments`, no refusal): H1
# fell in every run whose hand sphere cut into the platform there (7 runs, -2.5 to -0.5 cm)
# and in one of the three with 0-0.4 cm to spare (0.1 cm), and in none of the 8 with 0.8-2.1
# cm; HECTOR's smaller hands passed all 16 runs (8 scripts, both strategies) from -0.5 cm up.
# Looked for on a PREGRASP_STEP grid.
PREGRASP_GAP: Final = 0.005
PREGRASP_STEP: Final = 0.002
# How near (m) a hand point must come to an object's surface for the hand to close on it: the
# simulator's grasp model (locoplan.sim.grasp) and the plan's reach check of a grasp
# (locoplan.plan.payload) share it. The hand sphere (HAND_RADIUS) touches the surface at 2 cm,
# so a hand closing at 3 cm is 1 cm short of touching. HECTOR's: another robot's is its hand
# radius + 1 cm (`PlanGeometry.grasp_tolerance`, `locoplan.sim.robot_plan.plan_geometry`).
GRASP_TOLERANCE: Final = 0.03

# Minimum horizontal distance below which an approach direction is taken from the planned
# heading instead of from the robot-to-object vector (m).
APPROACH_MIN_DISTANCE: Final = 1e-6

# --- hand clearance (locoplan.plan.clearance) ------------------------------------------------
# Radius of HECTOR's hand collision spheres (m); robots/hector/hector.xml, geoms
# *_hand_sphere (`PlanGeometry.hand_radius`: robot.yaml `contacts.hand_radius`).
HAND_RADIUS: Final = 0.02
# Smallest gap (m) kept between a hand sphere and any object or fixture while the hands move
# towards or away from an object: the hands track their targets within about 2 cm.
APPROACH_CLEARANCE: Final = 0.025
# A hand that starts closer than that (resting beside an object) may come this much closer (m).
APPROACH_SLACK: Final = 0.005
# An approach whose best path comes nearer than this (m) to an object (not a fixture), though
# not into it, still tries the paths by way of the object's near corner
# (`hand_paths.approach_segments`), and takes a clear one: the hand's lag in the trunk frame
# (1-1.5 cm in fast turns, beside the yaw error that the check allows for) makes such a
# graze a push. H1 envelope seed 69027, transfer-017: the right hand's path passed 0.13 cm
# outside the parcel's margin, met the parcel at 1.56 s and turned it 38 deg; the grasp
# missed by 10 cm. Of that seed's 280 approaches, 2 came within this (the other 0.46 cm,
# placed its parcel), 4 within 2 cm.
OBJECT_GRAZE: Final = 0.01
# How far the trunk's yaw may be off the plan when hand paths are checked: YAW_LAG_TIME (s)
# times the planned yaw rate (the trunk lags about 4 deg at 1.8 rad/s in a loaded turn), and at
# least YAW_ERROR_MIN (rad).
YAW_LAG_TIME: Final = 0.04
YAW_ERROR_MIN: Final = math.radians(0.5)
# How far the trunk may be off its planned position when hand paths are checked (m): measured
# 2-3 cm of drift while turning in place.
TRUNK_POSITION_ERROR: Final = 0.02
# Within how much (m) two candidate hand paths' clearances from their nearest obstacles count
# as the same, so that the next-nearest decides (`clearance.Clearance.better_than`): a tenth
# of the hands' tracking error (about 2 cm, APPROACH_CLEARANCE), and above the spread of
# candidates whose nearest point is the same part of their paths (H1 seed 48027,
# transfer-033, the left hand's 1115 candidates nearest the conveyor: at most 0.8 mm at one
# sample time, 1e-16 m where the tucked hand passes it).
CLEARANCE_TIE: Final = 0.002
# Sampling period of the clearance check (s).
CLEARANCE_DT: Final = 0.01
# Most samples one clearance check takes (`clearance.track_clearance`): a window longer than
# MAX_CLEARANCE_SAMPLES x CLEARANCE_DT (100 s) is sampled more coarsely. The envelope's
# longest window is a whole locomotion script's (16.3 s on seed 90210), far inside it.
# Without the bound a script with a fixture 1e9 m away made `validate` sample a 9.5e9 s
# retreat every 10 ms and never return (found by tests/test_scenario_fuzz.py in CI).
MAX_CLEARANCE_SAMPLES: Final = 10000
# HECTOR's tucked hand pose of the LEFT hand in trunk (m; `PlanGeometry.hand_tuck_in_trunk`,
# robot.yaml `planner.hand_tuck`): close to the body and low, the forearms
# hanging forward: with the trunk at its nominal 0.60 m the hand sphere's top is at 0.38 m,
# below every table, platform and conveyor top of the envelope (0.40-0.55 m), and the hand
# stays within 0.16 m of the trunk axis, inside the nearest edge of anything the robot turns
# or walks towards (0.20 m). A tuck at table height (0.55 m) scraped tables 0.53 m high and
# boxes standing 0.20 m to the side of the robot as it turned (envelope seed 1, transfer-002).
HAND_TUCK_IN_TRUNK: Final = (0.06, 0.15, -0.24)
# Peak hand acceleration (m/s^2) of the moves that follow a release (opening, retreat). Both
# arms accelerating together push the trunk with about 2 x 0.5 kg x a (upper arm and forearm
# share), at about 0.55 m above the soles; the line feet answer a pitch moment of at most about
# 0.06 m x the weight (167 N): 10 N m, so a <= 0.5 x 10 / (0.55 x 1 kg) = 9 m/s^2 keeps half of
# it for balance. Retreats of 0.35 m in 0.28 s (26 m/s^2) and openings of 4 cm in 0.07 s
# (47 m/s^2) saturated the shoulders and tipped the robot after the release (envelope seed 1).
HAND_ACCEL_LIMIT: Final = 9.0
# The arms' share of that mass (kg, both arms: 2 x 0.5 kg). An object of mass m_o pulled in
# towards the trunk (`hand_paths.carry_in`) adds its own m_o a to the push, so its pull-in
# peaks at HAND_ACCEL_LIMIT ARM_MOVING_MASS / (ARM_MOVING_MASS + m_o) (`hand_paths.pull_accel`;
# 1.1 m/s^2 at 7 kg, 2.25 m/s^2 at 3 kg), the same 9 N on the trunk. Why: pulled in during the
# raise alone (5-9 m/s^2, 30-50 N), a 5.5-7.2 kg box drew the trunk towards it and saturated
# the stance hip pitch in the next single support (envelope seed 8080: transfer-004 at 2.28 s,
# walk-carry-001 at 1.53 s, both then fell).
ARM_MOVING_MASS: Final = 1.0
# Except for a heavy object, whose weight alone, m_o g times how far ahead it was picked, would
# take more than PULL_FAST_SHARE of the weakest leg joint's torque limit about the stance hip
# in single support: it comes the whole way in before the first step when the robot stands on
# both feet from the lift-off to then (the two hips share the pull's reaction), at the gentlest
# acceleration that allows (`manipulation._Builder._heavy_pull_accel`; the whole pull in the
# raise alone when nothing gentler ends by that step). Why: pulled in no faster than
# `pull_accel`, 6.2-7.8 kg boxes were still 0.25-0.33 m ahead in the first single support of the
# turn that followed and the stance hip pitch saturated (envelope seed 8080: 5 walk-carries fell
# that the fast pull carried); a 3.7 kg box pulled in fast drew the trunk after it and fell in
# the turn (transfer-001), slowly it did not; pulled in during the raise alone although the
# robot stood 0.5 s longer, 5-7 kg boxes drew the trunk 10 cm forward (seed 24681: the gentlest
# pull that ends by the first step took 12 -> 7 of its 180 transfer and walk-carry failures).
PULL_FAST_SHARE: Final = 0.5
# Time (s) to raise a tucked hand to the height of its reach target before reaching out.
TUCK_LIFT_DURATION: Final = 0.3
# Time to move a hand into the tucked pose (s), and how long before the first predicted
# collision of the direct path the tuck is complete (s).
TUCK_DURATION: Final = 0.4
TUCK_LEAD: Final = 0.1
# Step (s) by which the tuck is moved earlier when the tuck itself would pass too close.
TUCK_STEP: Final = 0.05
# Shortest reach from the tucked pose to the pre-grasp points (s): about 0.25 m at a peak speed
# below 1.9 m/s.
REACH_MIN_DURATION: Final = 0.25
# Step of the search for the earliest collision-free reach start (s).
REACH_START_STEP: Final = 0.02
