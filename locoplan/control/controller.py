"""The loco-manipulation controller: multi-contact MPC + swing/hand PD + whole-body mapping.

One `step(state)` per control tick (500 Hz; the loop holds the torques for two 1 ms physics
steps). Every `mpc_period` (10 ms) the MPC is re-solved over its horizon (20 x 0.03 s) with
the compiled plan's contact schedule, trunk reference, planned footholds and held-object force
inside the horizon. In between, the latest MPC wrenches are applied (zeroed for a foot that
has since lifted off).

Why the MPC is re-solved every 10 ms rather than every 30 ms: with the true composite inertia
(pitch about 0.6 kg m^2 rather than the trunk's 0.15) a 30 ms update made pitch oscillate at
the update rate on this robot (shared/controller-notes.md); 10 ms with the horizon still
20 x 0.03 s keeps the model honest and the loop stable.

Torque mapping, selectable:
- "wbc" (default): Kim et al.'s prioritised task accelerations (contacts, trunk orientation,
  trunk position, swing feet and hands, then a joint posture for the redundant joints, see
  `posture_joint_indices`) followed by the paper's WBC QP (locoplan.control.wbc).
- "jacobian": the plain baseline, tau = h - J_c' W for stance legs and tau = h + J' F_PD for
  swing legs and arms, plus a joint PD on the redundant joints.

The controller never imports mujoco: it sees pinocchio-convention states only.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
import numpy.typing as npt

from locoplan.control import reference_kernels, wbc_kernels
from locoplan.control.contact import ContactLimits, ankle_row_binds, ankle_torque_row
from locoplan.control.lean import TrunkLean
from locoplan.control.mpc import MpcInput, MpcSettings, MpcSolution, MultiContactMpc
from locoplan.control.recovery import (
    RecoverySchedule,
    capture_point,
    distance_outside,
    plan_recovery_step,
    plan_square_up_step,
    support_hull,
)
from locoplan.control.support import (
    chord_offsets,
    clamp_into_support,
    convex_hull,
    foot_segments,
    share_between_feet,
)
from locoplan.control.swing import min_jerk, smoothstep, smoothstep_array, swing_point
from locoplan.control.tasks import TaskGains, rot_z, rotation_error
from locoplan.control.wbc import (
    TASK_DAMPING,
    WbcOutput,
    WbcSettings,
    WholeBodyQp,
    prioritized_rows,
    wrench_world_to_w5,
)
from locoplan.control.wbc_kernels import stack_tasks
from locoplan.exceptions import SolverFailure
from locoplan.plan import HAND_NAMES, ObjectHold, Plan
from locoplan.plan.payload import equal_margin_share, grasp_reach_limit
from locoplan.robot.arm_range import narrowed_bounds, working_range
from locoplan.robot.conventions import pin_base_rotation
from locoplan.robot.description import RobotDescription
from locoplan.robot.pinocchio_model import PinocchioRobot

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

GRAVITY = 9.81
_GRAVITY_VECTOR = np.array([0.0, 0.0, -GRAVITY])  # (m/s^2, world; read-only)
_GRAVITY_VECTOR.flags.writeable = False
LOAD_RAMP = 1.0  # s over which a lifted (or placed) object's weight comes on (goes off)
# The weight goes off faster than it comes on: the plan lowers the object onto its support
# only in the last moments before the release, and carrying it while the controller already
# thinks it lighter made the hands sag and the robot fall forward after placing it.
LOAD_RAMP_DOWN = 0.6  # s
# Time constants of the hands' Cartesian PD (1/sqrt(kp), 50 ms at kp 400) over which a
# two-hand release eases the pair's separation back to the plan's (`_released_pair_targets`):
# 4 is the PD's settling time (2 %). Checked on the throws of envelope seeds 4711 and 27182
# (40 of 40 as before), 16180's throw-000 (fell without it) and the 276 manipulation scripts
# of seeds 4711 and 5000 (drops: the same runs succeed with and without it).
RELEASE_BLEND_TAU_RATIO = 4.0
# The hand-path segments (`locoplan.plan.hands.HandSegment.label`) that take a hand to a grasp:
# the hands track them at the robot's approach gains (robot.yaml `hand_approach_kp`).
APPROACH_LABELS = frozenset(("tuck", "lift", "reach", "slide"))
# Margin (m) inside the feet's support region (the hull of the line feet, toe to heel) that a
# standing CoM reference keeps: while both feet stand through the MPC's horizon, the plan's
# CoM reference (before the held-load lean) is moved to the nearest point that far inside.
# Why: a walk that ends behind its plan leaves the feet where they landed, and the plan's
# reference can then lie outside them; the MPC, asked for a CoM it cannot reach without a
# step, put both feet at their least force and the robot sank and fell (envelope seed 16180,
# locomotion-000: reference 6 cm outside the outer foot). 2 cm is about a third of the
# lateral room of the feet's nominal stance (0.16 m apart) and a third of the heel's length.
# Checked on the locomotion scripts of seeds 4711, 16180 and 27182 (120: one more succeeds,
# none lost) and the 276 manipulation scripts of seeds 4711 and 5000 (the same runs succeed).
STAND_SUPPORT_MARGIN = 0.02
# Least share of the weight a standing CoM reference leaves on each foot: after the clamp
# above, the reference is also moved along the line between the feet's centres to at least
# this fraction of their distance from each (`support.share_between_feet`; by the lever rule
# each foot then carries about that share at rest). Why: the clamp alone puts a reference
# that lies off the feet 2 cm inside the edge nearest to it, over one foot, and a line foot
# at the MPC's f_min or less holds no friction. HECTOR envelope seed 79021, dynamic
# transfer-054: the loaded turns (5.75 kg) left the robot 17 cm off its plan; standing to
# release the parcel, the reference came beside the left foot, the right carried 0-15 N,
# lifted and slid 13 cm inwards, and the robot fell at 6.51 s. With a quarter it carries
# 42-54 N and stays put (tests/test_stand_share.py). A quarter leaves the middle half of the
# distance between the feet free (every standing reference of a plan lies near its middle),
# and is 4x HECTOR's f_min at its weight (42 N of 166 N); chosen once, not tuned. Paired on
# the same scripts: HECTOR seed 79021 (both strategies) 397 -> 398 of 400 (transfer-054 fixed,
# none lost), H1 seed 72027 200 of 200 both.
STAND_FOOT_SHARE = 0.25
# Fastest change of the trunk's lean for a held load (rad/s; `_lean_limited`): the full
# 25 deg in 1.5 s. On envelope seed 44021's 33 heaviest or failing manipulation runs, 26
# succeed with it against 25 following the load's ramp (walk-carry-024 falls there) and 21
# without a lean; not tuned further.
LEAN_RATE = 0.3
LOAD_LEAD = 0.3  # s by which the CoM shift for a held load leads the load itself
# Time constant (s) of the low-pass filter on the measured hand load: above the 500 Hz tick's
# contact noise, well below the 0.6-1.0 s load ramps it corrects.
LOAD_FILTER_TAU = 0.03
# Below this fraction of its mass in the hands, a held object counts as resting on something:
# the hands stop lowering it (`step`). Pushing a box 1-3 cm further down onto its support (the
# trunk lags and leans, so the planned place height is a few cm off) had the robot lean on its
# hands, and it fell forward when they let go (envelope seed 1, transfer-021).
SUPPORTED_LOAD = 0.5
# Shortest time (s) over which the held-load CoM shift may go from the full load to none
# (`_update_load`). Checked from 0.2 to 0.6 s on pick-walk-drop, issue 12's example scripts and
# 80 envelope scripts (seed 1): with 0.6 s the unloaded robot stood for too long with its CoM
# leaning back against a load it no longer held (pick-walk-drop fell 1.2 s after its release).
LOAD_RELEASE_DECAY = 0.2
# Gap (m) a planned foothold keeps between the foot's sole segment (toe to heel) and every
# fixture's footprint: the sole spheres' and the foot box's 1 cm half-width plus 2 cm for the
# swing foot's tracking error at touchdown (measured 1-2 cm in envelope transfers).
FOOT_FIXTURE_CLEARANCE = 0.03
# Hip yaw (rad) kept free of a stance leg's share of a turn (`_mid_stance_yaw`): the trunk lags
# its yaw reference by up to 4-5 deg in loaded turns (the plan's YAW_LAG_TIME at 2 rad/s), and
# the swing foot lands within a few degrees of its planned yaw; 10 deg covers both, leaving
# 20 deg of HECTOR's 30 for the turn over a stance, which the envelope's transfers (up to
# 65 deg/s) reach only briefly. Checked on envelope seeds 8080 and 9191 (README).
HIP_YAW_MARGIN = math.radians(10.0)
# s: the time over which the footholds close the CoM's position error (`_foothold_from`).
# The foot lands d = 2 z / (g T_C) e / T the other way (z the CoM's height above the soles,
# T the gait period): over a stance of T / 2 the linear inverted pendulum turns that offset
# into a velocity change of e / T_C. 2.2 s reproduces on HECTOR (z / g = 0.0553 s^2) the
# gain 0.05 s that was measured on its envelopes (0.0503 s; seeds 24681, 8080, 30103, 11235,
# 27449, 33331) and gives H1 (0.0968 s^2) 0.088 s; checked on H1 envelope seeds 43019, 44027.
POSITION_CONVERGENCE_TIME = 2.2
# Recovery steps (`locoplan.control.recovery`): a standing robot whose capture point lies more
# than RECOVERY_MARGIN (m) outside its feet's soles steps, lifting the foot RECOVERY_LEAD (s)
# after the decision (the MPC, which sees the lift-off in its horizon from then on, moves the
# weight onto the other foot first; 0.05 s is the MPC's period 0.01 s five times over and its
# step 0.03 s well inside). The margin is the centre of pressure's own: the standing
# reference stays STAND_SUPPORT_MARGIN inside the soles, so a capture point 1 cm outside them
# is already 3 cm beyond where the MPC can bring the CoM to rest. Checked on HECTOR envelope
# seed 44021 (README).
RECOVERY_MARGIN = 0.01
RECOVERY_LEAD = 0.05
# Square-up steps (`locoplan.control.recovery.plan_square_up_step`): a foot whose distance
# from the centre of its standing nominal places exceeds half the stance width by more than
# SQUARE_UP_EXCESS widths steps back, lifting SQUARE_UP_LEAD swings after the decision.
# The excess: at the end of H1's walks on seed 72027 (33 locomotion runs, from their logs)
# feet stood up to 0.32 widths beyond without harm, and 71027's locomotion-034, which fell,
# 0.29; at a quarter width the step fires in 2 of H1 seed 72027's 200 runs and in 59 of
# HECTOR seed 79021's 400 (4 cm on its 0.16 m stance), every one of which succeeds (README,
# Envelope). The lead: the recovery step's 0.05 s is for a robot already falling; one swing
# gives the MPC that long to move the weight over the other foot and still fits the step and
# its settling (three swings, 0.66 s on H1) in locomotion-034's 0.8 s stand. Each is the
# first and only value tried.
SQUARE_UP_EXCESS = 0.25
SQUARE_UP_LEAD = 1.0
FEET = ("L", "R")
# Task rows a limb's end carries: a line foot 5 (position, foot pitch and yaw; stance or
# swing), a point hand 3 (position). A limb with more joints than that is redundant.
FOOT_TASK_ROWS = 5
HAND_TASK_ROWS = 3
# Singular values of the stacked task rows below this fraction of the largest count as zero
# when the posture task looks for their null space (`posture_in_null_space`): far above
# round-off (1e-15), far below the weakest real task direction (at the start of a stand,
# 0.068 of 3.0 on H1's 22 rows, 0.054 of 2.7 on HECTOR's).
NULL_SPACE_RTOL = 1e-6
# Share of the ankle's torque limit the MPC may plan a stance foot's wrench to need about the
# ankle axis, on a robot whose foot could otherwise ask for more than the limit
# (`ankle_mpc_settings`); the rest is the WBC's room for the trunk and swing tasks and the
# foot's own dynamics. Measured on H1's closed-loop scripts (step, push, walk, side-step,
# turn; tests/test_h1_closed_loop.py) with the bound at 1.0, 0.9 and 0.8 of the 40 N m: the
# ankles' peak followed it (1.00, 0.91-0.94, 0.81-0.84); without the bound every script held
# an ankle at its limit, the MPC planning up to 46 N m.
ANKLE_TORQUE_SHARE = 0.8
OBJECT_CACHE_SIZE = 2000  # memoised planned object positions kept before pruning
OBJECT_PREFETCH = 4  # MPC updates ahead whose object positions a miss evaluates too
CLIP_RTOL = 1e-9  # relative excess over a torque limit below which nothing counts as clipped


def rigid_pair_targets(targets: FloatArray, p_hands: FloatArray) -> FloatArray:
    """Targets (2, 3) for two hands holding one rigid object, from their planned targets (2, 3)
    and where they are (2, 3): the planned midpoint and the planned direction from the right
    hand to the left, at the hands' present separation.

    Why: the grasp fixes the hands to the object (`locoplan.sim.grasp`: a constraint per hand
    set where the hand is when it closes, up to GRASP_TOLERANCE from the side), so their
    separation is the object's. The plan's targets lie GRASP_SQUEEZE inside the sides, which
    asked the hands for 3-6 cm of squeeze the object forbids; the two Cartesian PDs then
    pushed against each other through the object, and with the 3-DoF arms the pair wobbled:
    hands 4-8 cm off their targets, one forward and up while the other went back and down,
    boxes tilted 20-30 deg and set down askew, and the opening hands dragged them off their
    target (envelope seeds 4711 and 5000: 6 light boxes ended on the floor). The separation
    is the object's; what the hands can still be asked is where the pair is and how it is
    turned, which keeps it level."""
    # (Norms as np.linalg.norm forms them for a vector, sqrt(d . d), without its checks:
    # this runs every tick while two hands hold.)
    d = targets[0] - targets[1]
    n = math.sqrt(d.dot(d))
    if n < 1e-9:
        return targets
    mid = 0.5 * (targets[0] + targets[1])
    span = p_hands[0] - p_hands[1]
    half = (0.5 * math.sqrt(span.dot(span)) / n) * d
    return np.array([mid + half, mid - half])


def rigid_pair_velocities(velocities: FloatArray, gap: FloatArray) -> FloatArray:
    """Velocity targets (2, 3) for two hands holding one rigid object: the planned ones
    (2, 3) less their relative velocity along the pair's axis (`gap`, the planned left hand
    less the right), shared equally; `rigid_pair_targets`' counterpart for the velocities.

    Why: the object fixes the hands' separation, and `rigid_pair_targets` holds the positions
    to it, but the planned velocities kept whatever separation the plan moves through. A
    throw eases its squeeze off in the 0.02 of its duration before the release (the hands
    from GRASP_SQUEEZE inside the sides to touching them, 3 cm in 21 ms for a 1.07 s
    throw): the hands' damping asked for 2-3 m/s of separation the grasp forbids, both
    shoulder rolls ran to 0.9 of their limit 10-20 ms before the release, the legs pushed
    324 N (the WBC planned 106), and the robot left the ground 5 cm and fell on landing
    (HECTOR envelope seed 89021, quasi-static throw-019: 1.73 kg at 2.2 m/s)."""
    n = math.sqrt(gap.dot(gap))  # np.linalg.norm's arithmetic (`rigid_pair_targets`)
    if n < 1e-9:
        return velocities
    u = gap / n
    along = float((velocities[0] - velocities[1]) @ u)
    out = np.array(velocities, dtype=float, copy=True)
    out[0] -= (0.5 * along) * u
    out[1] += (0.5 * along) * u
    return out


# The wall that keeps a joint inside its working range (`joint_wall_rows`): the joint may
# approach its bound no faster than it can stop there at WALL_TORQUE_SHARE of its torque
# limit over its own inertia at the nominal pose (`LocoManipulationController._wall_decel`;
# H1's elbow: 0.5 x 18 N m / 0.027 kg m^2 = 337 rad/s^2), brought to that speed with the
# time constant WALL_TAU (s). Checked on H1 envelope seeds 40009, 41011 and 42013. A PD on
# the bound (kp 100, kd 20, the posture gains) braked H1's elbow from
# 1.2 rad/s 0.15 rad before its bound, its hands lagged the reach for a box at full reach
# and the grasp closed late (envelope seed 41011, transfer-026); a fixed 50 rad/s^2 braked
# it at 6 rad/s 1.4 rad away and changed the reach of seed 40009's side-carry-013 (not
# placed). Half the torque leaves the rest for the arm's weight and a held load.
WALL_TORQUE_SHARE = 0.5
WALL_TAU = 0.05


def posture_joint_indices(desc: RobotDescription) -> npt.NDArray[np.intp]:
    """Joints (indices into `desc.joint_names`, sorted) that no task of the stack determines:
    the torso joints (no task uses them alone) and every joint of a limb with more joints than
    its end's task rows (FOOT_TASK_ROWS, HAND_TASK_ROWS). Empty for HECTOR (5-DoF legs, 3-DoF
    arms); H1: the torso yaw and both 4-DoF arms.

    Why the whole redundant limb rather than one chosen joint: the posture level is solved in
    the null space of the hand task, so on a 4-DoF arm under a 3-D hand task it can only move
    the one self-motion direction (the elbow circling the shoulder-hand line); which joint
    that direction mostly moves depends on the pose, and a posture on all four leaves the
    choice to the projection."""
    groups = [np.asarray(desc.torso_joint_indices, dtype=np.intp)]
    groups += [
        np.asarray(i, dtype=np.intp) for i in desc.leg_joint_indices if len(i) > FOOT_TASK_ROWS
    ]
    groups += [
        np.asarray(i, dtype=np.intp) for i in desc.arm_joint_indices if len(i) > HAND_TASK_ROWS
    ]
    return np.sort(np.concatenate(groups))


def posture_acceleration(
    cols: npt.NDArray[np.intp],
    q_des: FloatArray,
    q: FloatArray,
    v: FloatArray,
    kp: float,
    kd: float,
) -> FloatArray:
    """The joint posture PD: kp (q_des - q_j) - kd qdot_j (k,), rad/s^2, for the joints at
    velocity columns `cols` (k,) = j + 6, in pinocchio's q (joint j at q[7 + j]) and v (at
    v[6 + j]); `q_des` (k,) rad."""
    return kp * (q_des - q[cols + 1]) - kd * v[cols]


def joint_wall_rows(
    cols: npt.NDArray[np.intp],
    lower: FloatArray,
    upper: FloatArray,
    q: FloatArray,
    v: FloatArray,
    qdd: FloatArray,
    decel: FloatArray | float,
    tau: float = WALL_TAU,
) -> tuple[npt.NDArray[np.intp], FloatArray]:
    """The joints at velocity columns `cols` (k,) that `qdd` (nv,) would drive through their
    working bounds `lower` / `upper` (k,), rad (+-inf: no bound), and the acceleration
    (rad/s^2) each gets instead: (v_allowed - qdot_j) / tau, v_allowed the speed towards the
    bound from which `decel` (rad/s^2, per joint or one for all) still stops the joint at
    it, sqrt(2 decel distance) (the same speed away from it once past the bound). Returns
    (columns, accelerations); empty when no joint is driven past what it allows. q in
    pinocchio's layout (joint j at q[7 + j], velocity column j + 6).

    Compiled (`wbc_kernels.wall_rows`): it runs every control tick, and the same arithmetic
    over numpy arrays of two cost some 10 us a call (a tenth of the WBC tick), a Python
    loop 4-5 us inside the closed loop."""
    d = np.asarray(decel, dtype=np.float64)
    if d.ndim == 0:
        d = np.full(len(cols), float(d))
    return wbc_kernels.wall_rows(
        np.asarray(cols, dtype=np.intp),
        np.asarray(lower, dtype=np.float64),
        np.asarray(upper, dtype=np.float64),
        q,
        v,
        qdd,
        d,
        float(tau),
    )


def posture_in_null_space(
    J_tasks: FloatArray, cols: npt.NDArray[np.intp], a_posture: FloatArray, qdd: FloatArray
) -> FloatArray:
    """The joint accelerations (nv,) to add to `qdd` (nv,) so that the joints at velocity
    columns `cols` (k,) come as near as they can to `a_posture` (k,), rad/s^2, without
    changing J_tasks qdd for any task row above (J_tasks (n, nv)): least squares over the
    exact null space Z of J_tasks (right singular vectors of the singular values below
    NULL_SPACE_RTOL of the largest), dqdd = Z (S Z)^+ (a_posture - S qdd), S selecting `cols`.

    Why not one more level of `prioritized_rows`: its damped projections keep a fraction
    damping / (sigma^2 + damping) of each direction the levels above constrain (about 20 %
    of the weakest, sigma 0.07, of the contacts and trunk rows in double support), and a
    level that mostly asks for what the levels above forbid (a posture pulling the arms back
    while the hands move them) gets that leak amplified by up to 1 / (2 sqrt(damping)) = 16.
    Measured on H1 with the posture as a fourth damped level: at the first tick (hands 0.17 m
    from the plan's first target) it asked 1800 rad/s^2 of the knees and 300 m/s^2 of the
    trunk, every joint saturated and the robot fell at 0.57 s. In the exact null space the
    tasks above cannot feel it. (H1 in double support: 22 task rows over 25 columns, a 3-D
    null space: the torso yaw and each arm's elbow circle.)"""
    _, sv, Vt = np.linalg.svd(J_tasks)
    rank = int(np.count_nonzero(sv > NULL_SPACE_RTOL * sv[0])) if len(sv) else 0
    Z = Vt[rank:].T
    if Z.shape[1] == 0:
        return np.zeros_like(qdd)
    y = np.linalg.lstsq(Z[cols], a_posture - qdd[cols], rcond=None)[0]
    return np.asarray(Z.dot(y), dtype=np.float64)


def _nominal_q(robot: PinocchioRobot, desc: RobotDescription) -> FloatArray:
    """The nominal configuration (nq,): trunk upright at its nominal height over the origin,
    the nominal joint angles."""
    q0 = np.zeros(robot.nq)
    q0[2] = desc.base_height_nominal
    q0[6] = 1.0
    q0[7:] = desc.q_joints_nominal
    return q0


def mpc_body_inertia(robot: PinocchioRobot, desc: RobotDescription, body: str) -> FloatArray:
    """Rotational inertia (3, 3) (kg m^2, trunk axes = world at the nominal pose) of the MPC's
    rigid body, `robot` updated at the nominal pose: "composite", the whole robot's
    locked-joint inertia about its CoM; "upper-body", the bodies outside the legs (trunk,
    torso, arms) about their own CoM, the legs' mass counted only in the body's mass (lumped
    at the CoM).

    Why the choice: the MPC's state has the trunk's angular velocity where the centroidal
    dynamics have the whole robot's angular momentum. Locked joints say the legs turn with
    the trunk, but a stance leg's foot stays on the ground and a swing leg follows its own
    task: with heavy legs the composite inertia overstates what the trunk's rotation carries
    (H1, legs 42 % of the mass: pitch 5.27 kg m^2 composite, 0.96 upper body; HECTOR, legs
    18 %: 0.53 and 0.18). docs/robots.md compares the two on H1's closed-loop scripts."""
    if body == "composite":
        return np.asarray(robot.composite_inertia_world(), dtype=float)
    if body != "upper-body":
        raise ValueError(f"unknown MPC body {body!r}")
    legs = tuple(desc.joint_names[int(i)] for idx in desc.leg_joint_indices for i in idx)
    return robot.inertia_without_joints_world(legs)


def ankle_rows(robot: PinocchioRobot, desc: RobotDescription) -> tuple[FloatArray, float]:
    """The stance feet's ankle-moment row (5,) (`contact.ankle_torque_row`) and the smaller
    ankle torque limit (N m). The ankle is each leg's last joint (robot.yaml lists a leg hip
    to ankle); its axis and the sole site come from the model at the nominal pose (`robot`
    is updated there), in the foot's yaw frame, where they stay while the foot stands flat.
    The legs are mirror images: rows differing by more than 1e-9 raise ValueError
    (MpcSettings has one row for all feet)."""
    robot.update(_nominal_q(robot, desc), np.zeros(robot.nv))
    rows = []
    limits = []
    for leg, foot in zip(desc.leg_joint_indices, desc.foot_frames, strict=True):
        ankle = int(leg[-1])
        origin, axis_world = robot.joint_axis_world(desc.joint_names[ankle])
        sole = robot.frame_pose(foot)
        R = sole.R_to_world
        Rz = rot_z(math.atan2(R[1, 0], R[0, 0]))
        rows.append(ankle_torque_row(Rz.T.dot(axis_world), Rz.T.dot(sole.p_world - origin)))
        limits.append(float(desc.torque_limits[ankle]))
    if not np.allclose(rows[0], rows[1], rtol=0.0, atol=1e-9):
        raise ValueError(f"the legs' ankle rows differ: {rows[0]} vs {rows[1]}")
    return rows[0], min(limits)


def ankle_mpc_settings(
    mpc: MpcSettings, limits: ContactLimits, row: FloatArray, torque: float
) -> MpcSettings:
    """`mpc` with the stance ankle's torque bound, |row . w5| <= ANKLE_TORQUE_SHARE x torque,
    when the foot's other rows allow a wrench needing more than `torque` about the ankle
    (`contact.ankle_row_binds`); else `mpc` itself (HECTOR).

    Why: H1 steps with the CoM 0.2 m beside its stance foot and the MPC moves the centre of
    pressure towards the toe (up to 0.10 m of the 0.14 m) to stop the trunk pitching when the
    swing leg lifts; with 500 N on one foot, 0.08 m already asks the ankle for its 40 N m
    (the sole 0.07 m below the axis adds Fx' x 0.07). The WBC QP then held the ankle at its
    limit (no clip) and let the wrench deviate from the MPC's, every step. With the row the
    MPC plans within what the ankle holds, and the ankle peaks where the row puts it."""
    if not ankle_row_binds(row, limits, torque):
        return mpc
    r = tuple(float(x) for x in row)
    return replace(
        mpc,
        ankle_row=(r[0], r[1], r[2], r[3], r[4]),
        ankle_torque=ANKLE_TORQUE_SHARE * torque,
    )


def wrap_angle(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


def rpy_from_matrix(R: FloatArray) -> tuple[float, float, float]:
    """Roll, pitch, yaw (ZYX Euler, rad) of a rotation matrix."""
    yaw = math.atan2(R[1, 0], R[0, 0])
    pitch = -math.asin(max(-1.0, min(1.0, R[2, 0])))
    roll = math.atan2(R[2, 1], R[2, 2])
    return roll, pitch, yaw


@dataclass(frozen=True, slots=True)
class ControllerSettings:
    """Gains and rates. Trunk gains are the paper's Kp = diag(200, 200, 500, 1000, 1500,
    1000), Kd = diag(20, 20, 30, 30, 30, 30) on x_c = [p_c; Theta] (position first, as the
    paper defines x_c^des = [p_c^des; Theta^des]).

    The posture gains (1/s^2, 1/s) hold the joints no task determines
    (`posture_joint_indices`) at the nominal pose, as accelerations, so the same numbers
    serve any robot's inertia: kp 100 is a 10 rad/s bandwidth, half the hands' (kp 400), and
    kd = 2 sqrt(kp) damps it critically. HECTOR has no such joint and never uses them.

    Where these were checked: set on HECTOR (17 kg, trunk 0.60 m above the soles, foot
    0.15 m); the same numbers stand, step, walk, side-step and turn H1 (51.4 kg, 0.98 m,
    foot 0.175 m; tests/test_h1_closed_loop.py, HECTOR's gait of 0.4 s cycles and 0.15 s
    swings). The trunk, swing and hand gains are task accelerations, independent of mass.
    Tried on H1 and not kept, each scaled from HECTOR by H1's size: `swing_height` x 0.98 /
    0.60 = 0.13 m (pitch RMS stepping 0.58 -> 0.84 deg, walking 0.81 -> 0.98 deg, the
    pelvis 18 -> 29 mm RMS from the plan while walking: the heavy swing leg lifted higher
    shakes the trunk more) and `raibert_gain` x sqrt(0.98 / 0.60) = 0.064 s (within 1 mm RMS
    and 0.01 deg of HECTOR's value on every script). So they stay, checked over that range
    of sizes; the step that ends a walk uses the capture point's gain (`_foothold_from`).
    (The torsion bound does scale, with the foot's length: `contact.torsion_bound`.)"""

    mpc_period: float = 0.01
    mapping: Literal["wbc", "jacobian"] = "wbc"
    # The MPC's rigid body (`mpc_body_inertia`; robot.yaml `mpc_body`).
    mpc_body: Literal["composite", "upper-body"] = "composite"
    model: Literal["external-force", "combined"] = "external-force"
    qp_backend: str = "daqp"
    # The MPC must respect the line foot's small yaw friction like the WBC does: planning
    # turns on foot yaw moments (16 N m seen with a 4 kg box) spun the stance feet in place.
    mpc: MpcSettings = field(
        default_factory=lambda: MpcSettings(mu_torsion=ContactLimits().mu_torsion)
    )
    limits: ContactLimits = field(default_factory=ContactLimits)
    trunk_kp_pos: tuple[float, float, float] = (200.0, 200.0, 500.0)
    trunk_kd_pos: tuple[float, float, float] = (20.0, 20.0, 30.0)
    trunk_kp_rot: tuple[float, float, float] = (1000.0, 1500.0, 1000.0)
    trunk_kd_rot: tuple[float, float, float] = (30.0, 30.0, 30.0)
    # Swing foot: task-space acceleration gains (1/s^2, 1/s) for the WBC and Cartesian force
    # gains (N/m, N s/m) for the jacobian mapping (controller-notes: Kp 1000 / Kd 30 best).
    swing_kp_acc: float = 1500.0
    swing_kd_acc: float = 60.0
    swing_kp_force: float = 1000.0
    swing_kd_force: float = 30.0
    swing_kp_rot: float = 2000.0
    swing_kd_rot: float = 80.0
    swing_height: float = 0.08
    raibert_gain: float = 0.05
    # Whether the controller adds steps to the plan (`locoplan.control.recovery`): recovery
    # steps for a capture point outside the soles, square-up steps for a foot left far off.
    recovery_steps: bool = True
    # Whether the trunk leans back for a held load (`locoplan.control.lean`). Off: measured
    # about neutral on fresh envelope seeds (README, Envelope; CHANGELOG, Known limitations).
    trunk_lean: bool = False
    # The hands' Cartesian PD (1/s^2, 1/s): 20 rad/s, critically damped. A robot.yaml
    # `hand_approach_kp` (H1's) replaces it on the way to a grasp (`_hand_gains`); elsewhere
    # it stays: a holding hand's PD accelerates the object too (`_object_generalized_force`
    # feeds m_o a forward), so its stiffness costs the object's mass times kp per metre of
    # error, a squeezing hand's error is its press, and a hand opening beside what it set
    # down may touch it or its support. At kp 1500 HECTOR's 10 and 14 kg blocks went back on
    # their table after the grip (tests/test_manipulation.py), and an 8.95 kg block was put
    # back on its table with the retreating hands pushing on the table: the trunk rose 9 cm
    # and the robot fell (envelope seed 16339, standing-hold-000).
    hand_kp_acc: float = 400.0
    hand_kd_acc: float = 40.0
    hand_kp_force: float = 300.0
    hand_kd_force: float = 20.0
    posture_kp_acc: float = 100.0
    posture_kd_acc: float = 20.0


@dataclass(frozen=True, slots=True)
class ControlOutput:
    """Everything one tick decided: torques (n_joints,) before the last-guard clip, the clipped
    torques, how many joints were clipped, the applied contact wrenches (2, 6) world
    [F; M] at the soles (zero for swing feet), the stance flags, the swing and hand targets,
    and the latest MPC / WBC results (None when not run this tick)."""

    tau: FloatArray
    tau_clipped: FloatArray
    n_clipped: int
    wrench_world: FloatArray
    stance: tuple[bool, bool]
    foot_targets: FloatArray
    foot_yaw_targets: FloatArray
    hand_targets: FloatArray
    mpc: MpcSolution | None
    mpc_time_s: float
    wbc: WbcOutput | None
    wbc_time_s: float
    dynamics_time_s: float


@dataclass(slots=True)
class _SwingState:
    t_liftoff: float = -1.0
    p_start: FloatArray = field(default_factory=lambda: np.zeros(3))
    yaw_start: float = 0.0


class LocoManipulationController:
    """Stateful controller (MPC solver, latest MPC solution, swing start points)."""

    def __init__(
        self,
        robot: PinocchioRobot,
        desc: RobotDescription,
        plan: Plan,
        settings: ControllerSettings | None = None,
    ) -> None:
        self.robot = robot
        self.desc = desc
        self.plan = plan
        self.s = settings or ControllerSettings()
        row, ankle_torque = ankle_rows(robot, desc)
        self.mpc = MultiContactMpc(ankle_mpc_settings(self.s.mpc, self.s.limits, row, ankle_torque))
        self.wbc = WholeBodyQp(
            desc.torque_limits, WbcSettings(limits=self.s.limits, backend=self.s.qp_backend)
        )
        self.tau_limits = np.asarray(desc.torque_limits, dtype=float)
        self._neg_tau_limits = -self.tau_limits
        self._clip_limits = self.tau_limits * (1.0 + CLIP_RTOL)
        self._last_mpc: MpcSolution | None = None
        self._last_mpc_t = -math.inf
        self._last_contact = (True, True)
        self._swing = [_SwingState(), _SwingState()]
        # Planned touchdown points by (foot, touchdown time), refreshed at every MPC update
        # (10 ms) and shared by the MPC's horizon and the swing trajectories.
        self._footholds: dict[tuple[int, float], tuple[FloatArray, float]] = {}
        # Steps added to the plan's schedule (`_add_steps`).
        self.recovery = RecoverySchedule()
        self._shift_now = np.zeros(2)
        # The trunk's lean back for a held load now (rad; `TrunkLean`), updated with the MPC.
        self.lean = TrunkLean(robot) if self.s.trunk_lean else None
        self._lean_now = 0.0
        self._lean_t = -math.inf
        self._stand_offset = np.zeros(2)
        # Memoised planned object positions (`_planned_object_positions`): the row of each
        # time (us) in the store.
        self._object_rows: dict[int, int] = {}
        self._object_store = np.empty((256, 3))
        # Measured-load feedback (see `_update_load`): filtered measured mass (kg) and the
        # offset (kg) of the measurement from the plan's load now.
        self._load_filtered: float | None = None
        self._load_offset = 0.0
        self._shift_offset = 0.0
        self._load_t = -math.inf
        self._mass_now = 0.0
        self._supported = False
        self._mass_shift = 0.0
        # Last two-hand hold: (time, offset (3,) m of the pair's separation from the plan's).
        self._pair_release: tuple[float, FloatArray] = (-math.inf, np.zeros(3))
        self._pair_blend = RELEASE_BLEND_TAU_RATIO / math.sqrt(self.s.hand_kp_acc)
        # Each hand's grip height error (`_grip_corrected`): measured when its contact starts,
        # eased in over LOAD_RAMP s from its hold's lift-off, faded out over _pair_blend s
        # from the time the contact ended.
        self._grip_dz = np.zeros(2)
        self._grip_on = [False, False]
        self._grip_off = np.full(2, -math.inf)
        self._grip_lift = np.full(2, math.inf)
        self._grip_dz_max = grasp_reach_limit(plan.geometry)
        self._hold_mass = sum(h.mass for h in plan.holds)
        starts = {task.index: task.start for task in plan.tasks}
        self._drop_windows = [
            (starts[h.release_task], h.release)
            for h in plan.holds
            if h.release_kind == "drop" and h.release_task in starts
        ]
        # Joint columns in v (6 base columns first) of each leg and arm, in robot.yaml order,
        # and of the joints the posture task holds (none on HECTOR).
        self._cols_leg = [np.asarray(i, dtype=np.intp) + 6 for i in desc.leg_joint_indices]
        self._cols_arm = [np.asarray(i, dtype=np.intp) + 6 for i in desc.arm_joint_indices]
        posture = posture_joint_indices(desc)
        self._cols_posture = posture + 6
        self._q_posture = np.asarray(desc.q_joints_nominal, dtype=float)[posture]
        # Joints whose working range is narrower than their MJCF range (`working_range`: an
        # elbow that can fold past the straight arm; none on HECTOR), their columns and bounds.
        # Only the narrowed side is walled: MuJoCo's joint limit holds the MJCF side, and a
        # wall there braked H1's elbow from 10 rad/s 1.3 rad before its -1.25 rad stop in
        # the tuck, which threw the arms about (envelope seed 41011, side-carry-003, fell).
        wall_lo, wall_hi = narrowed_bounds(desc, *working_range(robot))
        walled = np.flatnonzero(np.isfinite(wall_lo) | np.isfinite(wall_hi))
        self._cols_wall = walled.astype(np.intp) + 6
        self._wall_lower = wall_lo[walled]
        self._wall_upper = wall_hi[walled]
        self._wall_decel = np.zeros(len(walled))
        if len(walled):
            robot.update(_nominal_q(robot, desc), np.zeros(robot.nv))
            inertia = np.diag(robot.M)[walled + 6]
            self._wall_decel = WALL_TORQUE_SHARE * self.tau_limits[walled] / inertia
        # Frames read every tick, in `step`'s order: feet, hands, trunk.
        self._frames = (*desc.foot_frames, *desc.hand_frames, desc.trunk_body)
        s = self.s
        self._gains = TaskGains(
            s.trunk_kp_pos,
            s.trunk_kd_pos,
            s.trunk_kp_rot,
            s.trunk_kd_rot,
            s.swing_kp_acc,
            s.swing_kd_acc,
            s.swing_kp_rot,
            s.swing_kd_rot,
        ).packed()
        # Per hand (left, right): the approach or the other gains (`_hand_gains`).
        self._hand_kp = np.full((2, 1), s.hand_kp_acc)
        self._hand_kd = np.full((2, 1), s.hand_kd_acc)
        self._hand_ff = np.zeros((2, 1))
        # On the way to a grasp (`_hand_gains`): the robot's approach gains, if it states any.
        kp_a = desc.hand_approach_kp
        self._approach_gains = None if kp_a is None else (kp_a, 2.0 * math.sqrt(kp_a))
        if s.mapping == "wbc":
            wbc_kernels.warm_up(robot.nv)
        reference_kernels.warm_up()
        self._nominal_geometry()
        # Each hold that leans before its lift-off, when it leans, and where (x, y) its object
        # is gripped at the lift-off (`_pre_lean`; the plan fixes it, so once here).
        self._pre_lean_windows = [
            (
                h,
                *self._pre_lean_window(h),
                self._planned_object_positions(np.array([h.lift + 1e-3]))[0, :2],
            )
            for h in plan.holds
            if self._leans_before_lift(h)
        ]
        # The holds whose weight the hands take at the lift-off (`_lift_mass`).
        self._on_time_lifts = tuple(h for h in plan.holds if self._steps_after_lift(h))
        # The heavy standing holds whose weight comes on no faster than the load ramp.
        self._slow_lifts = tuple(
            h for h in plan.holds if h.slow_lift and h not in self._on_time_lifts
        )

    def _keep_in_working_range(
        self,
        J_t: FloatArray,
        b_t: FloatArray,
        a_t: FloatArray,
        ends: npt.NDArray[np.int64],
        q: FloatArray,
        v: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        """The task stack's accelerations (`prioritized_rows` on J_t, a_t - b_t, ends) under a
        first level that stops each joint they would drive through its working bound
        (`joint_wall_rows`), solved again under it; and the stack's rows with that level on
        top (J_t unchanged when no joint is driven there), for the posture's null space.
        The hands then follow their targets as far as the rest of the arm allows: on H1
        (`locoplan.robot.arm_range`) a hand pulled in from full reach bends the elbow the
        nominal way instead of straightening it through the singularity and folding it
        backwards onto its stop.

        One compiled call (`wbc_kernels.prioritized_walled`: the two solves and the wall,
        the same arithmetic as three calls and numpy's stacking, so the same values to the
        bit); the walled rows are stacked here only where a posture task needs them."""
        try:
            qdd, cols, _ = wbc_kernels.prioritized_walled(
                J_t,
                a_t,
                b_t,
                ends,
                TASK_DAMPING,
                self._cols_wall,
                self._wall_lower,
                self._wall_upper,
                q,
                v,
                self._wall_decel,
                WALL_TAU,
            )
        except np.linalg.LinAlgError:
            # Not positive definite: cannot happen with finite data (`prioritized_rows`).
            return J_t, np.full(J_t.shape[1], np.nan)
        n = len(cols)
        if n and len(self._cols_posture):
            rows = np.zeros((n, J_t.shape[1]))
            rows[np.arange(n), cols] = 1.0
            J_t = np.vstack((rows, J_t))
        return J_t, qdd

    # -- set-up --------------------------------------------------------------------------------
    def _nominal_geometry(self) -> None:
        """CoM offset and foot offsets in the trunk's yaw frame at the nominal pose, and the
        MPC's body inertia (`mpc_body_inertia`, trunk frame)."""
        r = self.robot
        q0 = _nominal_q(r, self.desc)
        r.update(q0, np.zeros(r.nv))
        base = q0[:3]
        self.com_offset = r.com_position - base  # trunk frame == world at yaw 0
        self.foot_offsets = np.array([r.frame_position(f) - base for f in self.desc.foot_frames])
        self.hand_offsets = np.array([r.frame_position(h) - base for h in self.desc.hand_frames])
        self.inertia_body = mpc_body_inertia(r, self.desc, self.s.mpc_body)
        self.mass = float(r.total_mass)
        # Foot placement relative to the CoM (x: support centre under the CoM).
        self.foot_offset_from_com = self.foot_offsets - self.com_offset
        self.com_height = float(r.com_position[2])
        # The last step's foothold velocity gain (s): the capture point's sqrt(z / g), z the
        # CoM's height above the soles (HECTOR 0.23 s, H1 0.31 s; `_foothold_from`).
        above_soles = float(self.com_offset[2] - np.mean(self.foot_offsets[:, 2]))
        self._capture_gain = math.sqrt(above_soles / GRAVITY)
        # The footholds' gain on the CoM's position error (s; `POSITION_CONVERGENCE_TIME`).
        self._position_gain = 2.0 * above_soles / (GRAVITY * POSITION_CONVERGENCE_TIME)
        self._last_touchdowns: dict[float, bool] = {}
        # `_free_to_step`'s sample offsets per lead (np.linspace costs 10 us a call).
        self._step_samples: dict[float, FloatArray] = {}
        # How far the nominal CoM stands ahead of the middle of the feet's support (m, along
        # the feet; robot.yaml's toe and heel about the sole site): see `_lean_share`.
        sole_x = float(np.mean(self.foot_offsets[:, 0]))
        middle = sole_x + (self.desc.foot_toe - self.desc.foot_heel) / 2.0
        self._support_offset = float(self.com_offset[0]) - middle
        # The hip yaw a stance leg may take while the trunk turns over it (rad, `_mid_stance_
        # yaw`): the smaller side of the legs' first joint's range (the hip yaw, robot.yaml)
        # less HIP_YAW_MARGIN.
        hip = [int(legs[0]) for legs in self.desc.leg_joint_indices]
        lo = min(-float(self.desc.q_lower[j]) for j in hip)
        hi = min(float(self.desc.q_upper[j]) for j in hip)
        self._hip_yaw_room = max(min(lo, hi) - HIP_YAW_MARGIN, 0.0)

    # -- helpers -------------------------------------------------------------------------------
    def _com_reference(
        self, times: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        """CoM position (n,3), velocity (n,3), yaw (n,), yaw rate (n,) from the plan, and the
        trunk-origin position (n,3) it came from."""
        ref = self.plan.trunk_reference(times)
        yaw = np.asarray(ref.yaw, dtype=float)
        c, s = np.cos(yaw), np.sin(yaw)
        off = self.com_offset
        p = np.array(ref.position, dtype=float)
        p[:, 0] += c * off[0] - s * off[1]
        p[:, 1] += s * off[0] + c * off[1]
        p[:, 2] = self.com_height + (p[:, 2] - self.desc.base_height_nominal)
        v = np.array(ref.velocity, dtype=float)
        w = np.asarray(ref.yaw_rate, dtype=float)
        # d/dt of the rotated offset.
        v[:, 0] += -w * (s * off[0] + c * off[1])
        v[:, 1] += w * (c * off[0] - s * off[1])
        return p, v, yaw, w, np.asarray(ref.position, dtype=float)

    def _mid_stance_yaw(self, k: int, t_td: float, yaw_td: float) -> float:
        """The yaw (rad) foot k lands with at t_td, continuous with yaw_td (the reference yaw
        at touchdown, which may be unwrapped): yaw_td turned on by o = clip(d - R, 0, d / 2)
        towards the turn, d the reference's turn over the stance (to the foot's next
        lift-off; a last stance counts one gait period) and R = `_hip_yaw_room`.

        Why: while the foot stands, the trunk turns on by d, so a foot landed at the
        touchdown yaw ends its stance d behind the trunk, all of it on one side of the hip yaw
        range; turned on by o it spans -o .. d - o, so the leg stays within R where d > R
        (o = d / 2 centres the turn on the foot). At the envelope's fastest turns (90 deg/s
        average, the min-jerk peak 169 deg/s, stances of 0.15-0.3 s) d reaches 25-50 deg:
        both hip yaws ran to HECTOR's +30 deg mid-turn and the robot fell (envelope seed
        8080, locomotion-009, -020, -036; all three succeed with it). Only as much as the
        range needs: a larger o is a larger yaw rotation of the swing foot, whose reaction
        the stance foot's little yaw friction must hold, and always centring every stance
        (o = d / 2) lost 3 of 60 transfers on each of seeds 8080 and 9191 (loaded turns at up
        to 65 deg/s, d up to 30 deg) against the locomotion it gained."""
        lift = self.plan.next_liftoff(k, t_td + 1e-9)
        t_lift = t_td + self.plan.gait_period_at(t_td) if lift is None else lift
        d = wrap_angle(float(self.plan.trunk.pose_at(t_lift)[2]) - yaw_td)
        o = min(max(abs(d) - self._hip_yaw_room, 0.0), 0.5 * abs(d))
        return yaw_td + math.copysign(o, d)

    def _add_steps(
        self,
        t: float,
        p_c: FloatArray,
        v_c: FloatArray,
        p_feet: FloatArray,
        yaw_feet: FloatArray,
        yaw_ref: float,
    ) -> None:
        """Add a step to the plan's schedule (`locoplan.control.recovery`) for the CoM p_c (3,)
        moving at v_c (3,), when no added step is under way or settling: a recovery step when
        the capture point lies more than RECOVERY_MARGIN outside the soles, a square-up step
        (`_square_up`) when it lies inside them; each only while the plan has both feet down
        and the hands touching nothing (`_free_to_step`) for the step and a swing's settling
        after it."""
        swing = self.plan.gait_swing
        if self.recovery.busy(t, swing) or not self._free_to_step(t, RECOVERY_LEAD):
            return
        xi = capture_point(p_c, v_c, self._capture_gain)
        toe, heel = self.desc.foot_toe, self.desc.foot_heel
        outside = distance_outside(xi, support_hull(p_feet, yaw_feet, toe, heel))
        if outside == 0.0:
            self._square_up(t, p_feet)
            return
        if outside <= RECOVERY_MARGIN:
            return
        width = float(abs(self.foot_offsets[0, 1] - self.foot_offsets[1, 1]))
        step = plan_recovery_step(
            t,
            xi,
            p_feet,
            yaw_feet,
            yaw_ref,
            toe,
            heel,
            width,
            self.plan.geometry.walk_stride,
            self._capture_gain,
            RECOVERY_LEAD,
            swing,
        )
        if self.plan.footprints:
            self._off_footprints(step.target, step.yaw)
        self.recovery.steps.append(step)

    def _free_to_step(self, t: float, lead: float) -> bool:
        """Whether the plan keeps both feet down and the hands touching nothing
        (`hand_contact_flags`) from t over a step lifting `lead` (s) later and a swing's
        settling after it (8 samples).

        The hands: not while they hold or grip something. The capture point is a point
        mass's; a held load is a second mass the arms and the CoM shift move about (or its
        support still carries), which it does not describe: lifting 10-13 kg blocks, HECTOR's
        capture point (of robot and load together, or of the robot alone) left its soles by
        2-6 cm while it stood through the lift, and the steps taken then set off a cascade of
        steps and a fall (seed 44021, standing-hold-006, -013). Nor when they will before the
        step is done: the trunk leaning back before a 12.6 kg lift took the capture point past
        the heels just before the grasp (the step lifted off 0.05 s after it), and the left
        foot rose as the block came off its table; the stance hip pitch saturated and the
        robot fell (seed 76021, standing-hold-014, both strategies). Without the step it
        holds the block."""
        offsets = self._step_samples.get(lead)
        if offsets is None:
            offsets = np.linspace(0.0, lead + 2.0 * self.plan.gait_swing, 8)
            self._step_samples[lead] = offsets
        ahead = t + offsets
        if not bool(np.all(self.plan.contact_flags(ahead))):
            return False
        return not bool(np.any(self.plan.hand_contact_flags(ahead)))

    def _square_up(self, t: float, p_feet: FloatArray) -> None:
        """Add a square-up step (`locoplan.control.recovery.plan_square_up_step`) for feet at
        p_feet (2, 3) standing at rest, lifting SQUARE_UP_LEAD gait swings from t (when
        `_free_to_step` over it), if one of them stands far from its nominal place about the
        plan's CoM reference (where `_foothold_from` puts the foot of a CoM at rest on its
        reference)."""
        swing = self.plan.gait_swing
        lead = SQUARE_UP_LEAD * swing
        if not self._free_to_step(t, lead):
            return
        p_ref, _, yaw_ref, _, _ = self._com_reference(np.array([t]))
        yaw = float(yaw_ref[0])
        nominal = p_ref[0] + self.foot_offset_from_com @ rot_z(yaw).T
        width = float(abs(self.foot_offsets[0, 1] - self.foot_offsets[1, 1]))
        step = plan_square_up_step(
            t, p_feet, nominal, yaw, width, SQUARE_UP_EXCESS * width, lead, swing
        )
        if step is None:
            return
        if self.plan.footprints:
            self._off_footprints(step.target, step.yaw)
        self.recovery.steps.append(step)

    def _foothold(
        self, k: int, t: float, t_td: float, p_c: FloatArray, v_c: FloatArray
    ) -> tuple[FloatArray, float]:
        """Planned touchdown point (3,) and yaw of foot k for a touchdown at `t_td` (paper's
        Raibert rule on top of the reference's planned displacement)."""
        p_ref, v_ref, yaw_ref, _, _ = self._com_reference(np.array([t, t_td]))
        return self._foothold_from(k, t_td, p_c, v_c, p_ref, v_ref, float(yaw_ref[1]))

    def _last_touchdown(self, t_td: float) -> bool:
        """Whether the touchdown at t_td (s) ends its locomotion: no foot swings in the gait
        period after it. Memoised per touchdown (the plan is fixed; the MPC asks for every
        touchdown in its horizon at each update, and asking the plan each time cost 0.1 ms
        per update)."""
        last = self._last_touchdowns.get(t_td)
        if last is None:
            period = self.plan.gait_period_at(t_td)
            times = t_td + period * np.linspace(0.05, 1.0, 8)
            last = bool(np.all(self.plan.contact_flags(times)))
            self._last_touchdowns[t_td] = last
        return last

    def _foothold_from(
        self,
        k: int,
        t_td: float,
        p_c: FloatArray,
        v_c: FloatArray,
        p_ref: FloatArray,
        v_ref: FloatArray,
        yaw_td: float,
    ) -> tuple[FloatArray, float]:
        """`_foothold` given the CoM reference now and at touchdown: p_ref and v_ref (2, 3)
        rows [now, touchdown], yaw_td the reference yaw at touchdown (rad).

        The foot is yawed (and its offset from the CoM turned) to `_mid_stance_yaw`: the
        reference yaw at touchdown, turned on towards the turn where the trunk's turn over
        the stance would take the hip yaw beyond its room."""
        yaw_td = self._mid_stance_yaw(k, t_td, yaw_td)
        off = rot_z(yaw_td) @ self.foot_offset_from_com[k]
        stance_time = self.plan.gait_period_at(t_td) / 2.0
        # Relative to where the CoM would be without the held-load shift: the feet must keep
        # the support centre under the planned trunk, with the CoM shifted back over them
        # (placing them relative to the shifted CoM walked the robot backwards under a load).
        p = p_c + (p_ref[1] - p_ref[0]) + off
        p[:2] -= self._shift_now
        # The paper's rule: the measured CoM velocity's neutral point v_c dt/2, plus k times
        # its error (k = `raibert_gain`). The step that ends a walk or turn (`_last_
        # touchdown`) takes k = sqrt(z_com / g) instead, the linear inverted pendulum's time
        # constant: a foot placed v sqrt(z / g) ahead of the CoM is where the CoM's motion
        # comes to rest over it (the capture point; the same term as in MIT Cheetah 3's convex
        # MPC, Di Carlo et al. 2018; HECTOR 0.23 s, H1 0.31 s). With 0.05 there, H1, stopping
        # from a loaded walk 0.2-0.3 m/s faster than its reference, put its last foot 1.5 cm
        # ahead for it instead of 9 cm; the CoM ran on past its ankle-torque-bound centre of
        # pressure at 0.16 m/s and the robot fell forward 1-1.5 s later while placing the box
        # (envelope seed 40009, walk-carry-005, -014, -023: all four place their box with
        # it). On every step, sqrt(z / g) fed the gait's sway back into the footholds: 4 of
        # that seed's 40 H1 locomotion scripts fell (0.15 s: 1 of those 4).
        # Why measured (as the paper has it) and not the reference's velocity at
        # touchdown, which this used before: a velocity error was then fed back through k =
        # 0.05 alone, and a line foot cannot push the CoM sideways in single support; the
        # first single support of an in-place turn with 0.23 s swings let the CoM fall 5 cm
        # towards the swing foot, every foot after landed the nominal width from the moving
        # CoM, and the robot walked off sideways at 0.15-0.2 m/s until it fell (envelope seed
        # 31415, locomotion-013, -038, -039, both strategies; all six succeed with it).
        gain = self._capture_gain if self._last_touchdown(t_td) else self.s.raibert_gain
        p[:2] += v_c[:2] * stance_time / 2.0 + gain * (v_c[:2] - v_ref[0, :2])
        # The CoM's position error fed back as a velocity, closed over a gait period T:
        # wanting v_ref + e / T, the foot lands raibert_gain e / T the other way (the CoM
        # falls away from its foot). Why: the footholds above follow the measured CoM, and
        # with swings of nearly half the period the feet stand together for milliseconds, so
        # a line foot cannot push the CoM sideways and nothing brought it back to its
        # reference: walking 0.94 m while turning 49 deg, HECTOR drifted 0.27 m to its side
        # of the path, and the sideways walk that followed fell (envelope seed 27449,
        # locomotion-005, both strategies). Measured: HECTOR fresh seed 33331 396 of 400
        # with it, 393 without; dynamic locomotion of seeds 24681, 8080, 30103, 11235 160
        # of 160 against 159. The gain is the robot's (`POSITION_CONVERGENCE_TIME`): with
        # HECTOR's 0.05 s, H1 seed 43019 (dynamic) lost locomotion-008 (198 of 200 against
        # 199 without the feedback); with its own 0.088 s, 199 of 200.
        error = p_ref[0, :2] + self._shift_now - p_c[:2]
        p[:2] -= self._position_gain * error / (2.0 * stance_time)
        p[2] = 0.0
        if self.plan.footprints:
            self._off_footprints(p, yaw_td)
        return p, yaw_td

    def _off_footprints(self, p: FloatArray, yaw: float) -> None:
        """Move the foothold p (3,) (in place) out of every fixture's footprint grown by
        FOOT_FIXTURE_CLEARANCE, for a foot yawed `yaw`: its toe, sole site and heel points are
        pushed out across the nearest side, a few passes for corners and neighbours.

        Why: fixtures are solid from the floor, and a turn in place between a table and a
        target whose near edges are 0.15-0.25 m from the trunk axis sweeps the toes (0.09 m
        ahead of the ankle, 0.1 m to its side) within a few cm of them; with the few cm the
        trunk drifts under a load, the Raibert rule put feet on the fixtures' sides and the
        robot tripped (envelope seed 11: a foot touched a fixture before 26 of 31 falls)."""
        c, s = math.cos(yaw), math.sin(yaw)
        toe, heel = self.desc.foot_toe, -self.desc.foot_heel
        points = ((toe * c, toe * s), (0.0, 0.0), (heel * c, heel * s))
        grow = FOOT_FIXTURE_CLEARANCE
        for _ in range(3):
            moved = False
            for fx, fy, fyaw, hx, hy in self.plan.footprints:
                cf, sf = math.cos(fyaw), math.sin(fyaw)
                for ox, oy in points:
                    dx, dy = p[0] + ox - fx, p[1] + oy - fy
                    u, v = cf * dx + sf * dy, -sf * dx + cf * dy
                    du, dv = hx + grow - abs(u), hy + grow - abs(v)
                    if du <= 0.0 or dv <= 0.0:
                        continue
                    if du < dv:
                        step = math.copysign(du, u)
                        p[0] += step * cf
                        p[1] += step * sf
                    else:
                        step = math.copysign(dv, v)
                        p[0] -= step * sf
                        p[1] += step * cf
                    moved = True
            if not moved:
                return

    # -- MPC -----------------------------------------------------------------------------------
    def _run_mpc(
        self,
        t: float,
        x0: FloatArray,
        p_c: FloatArray,
        v_c: FloatArray,
        p_feet_now: FloatArray,
        yaw_feet_now: FloatArray,
        p_hands_mid: FloatArray,
        mass_now: float,
    ) -> MpcSolution:
        """One MPC update at t. The plan is queried once per update: the trunk reference at
        the horizon's times, now, and each planned touchdown inside the horizon in one
        vectorised evaluation."""
        N = self.s.mpc.horizon
        dt = self.s.mpc.dt
        plan = self.plan
        times = t + dt * np.arange(1, N + 1, dtype=np.float64)
        # Touchdowns inside the horizon: the stance a foot will be in at each step started
        # after t (NaN: the initial stance, compares False).
        td = np.stack(
            [self.recovery.stance_starts(k, times, plan.stance_starts(k, times)) for k in range(2)]
        )
        future = td > t + 1e-9
        keys = sorted({(k, x) for k in range(2) for x in td[k][future[k]].tolist()})
        # The held-load CoM shift now and at the horizon's steps (lead times t + LOAD_LEAD and
        # times + LOAD_LEAD) joins the same evaluation when a load is on.
        t_lead = np.concatenate([[t], times]) + LOAD_LEAD
        mass_lead = self.shift_mass(t_lead)
        loaded = bool(np.any(mass_lead > 0.0)) or any(
            t0 <= t < h.lift + LOAD_RAMP for h, t0, _, _ in self._pre_lean_windows
        )
        n_td = len(keys)
        eval_times = np.concatenate(
            [times, [t], [x for _, x in keys], t_lead if loaded else np.zeros(0)]
        )
        p_all, v_all, yaw_all, w_all, pb_all = self._com_reference(eval_times)
        contact = self.recovery.flags(times, np.asarray(plan.contact_flags(times), dtype=bool))
        self._stand_offset = np.zeros(2)
        support: tuple[FloatArray, FloatArray] | None = None
        standing: BoolArray | None = None
        if contact[0].all() and (loaded or contact.all()):
            hull = convex_hull(
                foot_segments(p_feet_now, yaw_feet_now, self.desc.foot_toe, self.desc.foot_heel)
            )
            if contact.all():
                # Standing through the horizon: the reference over the feet
                # (STAND_SUPPORT_MARGIN).
                inside = clamp_into_support(p_all[0, :2], hull, STAND_SUPPORT_MARGIN)
                mid = (self.desc.foot_toe - self.desc.foot_heel) / 2.0
                heading = np.stack((np.cos(yaw_feet_now), np.sin(yaw_feet_now)), axis=1)
                c0, c1 = p_feet_now[:2, :2] + mid * heading[:2]
                inside = share_between_feet(inside, c0, c1, STAND_FOOT_SHARE)
                self._stand_offset = inside - p_all[0, :2]
            # The feet as they stand count for the rows before the horizon's first step
            # (`_com_shift`; all of them while standing through it).
            support = (p_all[0, :2] + self._stand_offset, hull)
            standing = np.concatenate(([True], np.cumprod(contact.all(axis=1)).astype(bool)))
        shift = (
            self._com_shift(t_lead, mass_lead, p_all[N + 1 + n_td :], support, standing)
            if loaded
            else np.zeros((N + 1, 2))
        )
        # Updated with the MPC and held in between (it follows the load ramp, about 1 mm per
        # MPC period at most): the footholds below and the trunk task use it.
        self._shift_now = shift[0]
        p_ref, v_ref, yaw_ref, w_ref = p_all[:N], v_all[:N], yaw_all[:N], w_all[:N]
        x_ref = np.zeros((N, 15))
        x_ref[:, 2] = yaw_ref
        x_ref[:, 3:6] = p_ref
        x_ref[:, 8] = w_ref
        x_ref[:, 9:12] = v_ref
        x_ref[:, 14] = -GRAVITY
        x_ref[:, 3:5] += self._stand_offset
        p_feet = np.repeat(p_feet_now[None], N, axis=0)
        foot_yaw = np.repeat(yaw_feet_now[None], N, axis=0)
        self._footholds.clear()
        for j, (k, t_td) in enumerate(keys):
            rows = [N, N + 1 + j]
            added = self.recovery.at_touchdown(k, t_td)
            fh = (
                (added.target, added.yaw)
                if added is not None
                else self._foothold_from(
                    k, t_td, p_c, v_c, p_all[rows], v_all[rows], float(yaw_all[N + 1 + j])
                )
            )
            self._footholds[(k, t_td)] = fh
            at = future[k] & (td[k] == t_td)
            p_feet[at, k] = fh[0]
            foot_yaw[at, k] = fh[1]
        obj_mass = self.carried_mass(times)
        held = obj_mass > 0.0
        # Where nothing is held object_positions gives the trunk position: skip the call.
        p_obj = self._planned_object_positions(times) if held.any() else pb_all[:N].copy()
        if mass_now > 0.0:
            # Feedback on where the load really is: the object sits between the hands, which
            # lag their planned path (most when the robot turns with a load); shift the
            # planned object path by today's error.
            planned_now = self._planned_object_positions(np.array([t]))[0]
            p_obj = p_obj + (p_hands_mid - planned_now)
        x_ref[:, 3:5] += shift[1:]
        if self.lean is not None:
            lead_rows = slice(N + 1 + n_td, None)
            lean = self._lean(t, t_lead, mass_lead, pb_all[lead_rows], yaw_all[lead_rows])
            lean = self._lean_limited(t, dt, lean)
            self._lean_now = float(lean[0])
            x_ref[:, 1] = -lean[1:]
        a_obj = self._planned_object_accelerations(t, dt, N) if held.any() else None
        inp = MpcInput(
            x0=x0,
            x_ref=x_ref,
            contact=contact,
            p_feet=p_feet,
            foot_yaw=foot_yaw,
            yaw_lin=yaw_ref,
            mass=self.mass,
            t=t,
            inertia_body=self.inertia_body,
            object_held=held,
            object_mass=obj_mass,
            p_object=p_obj,
            a_object=a_obj,
            model=self.s.model,
        )
        return self.mpc.update(inp)

    def _lean(
        self, t: float, times: FloatArray, mass: FloatArray, p_ref: FloatArray, yaw_ref: FloatArray
    ) -> FloatArray:
        """The trunk's lean back (rad, `TrunkLean`), decided at t, at `times` (n,) for the
        held-load masses `mass` (n,) the CoM shift uses there, the load held where the plan
        puts the object, ahead of the trunk reference's position and heading there (p_ref
        (n, 3), yaw_ref (n,)). Zero where nothing is held, with `trunk_lean` off, and unless
        a held object's load is wholly on at t (from LOAD_RAMP after its lift-off to its
        release; not for throws).

        Why not from the lift-off (led by LOAD_LEAD like the CoM shift): the lift is the
        transient in which a heavy box's weight pulls the CoM towards it; a lean coming on
        then, pitching the trunk back, pushed the CoM further forward, past the toes (envelope
        seed 46021: walk-carry-006 and -027 in both strategies, 7.2-7.4 kg, fell in or just
        after the lift with the lean from the lift-off). On the thirteen runs of that seed
        whose outcome the early lean changed, 11 succeed with this one against 7 without a
        lean (walk-carry-011 in both strategies, transfer-003 and -026 gained, none lost)."""
        if self.lean is None or not np.any(mass > 0.0):
            return np.zeros(len(times))
        if not any(
            h.lift + LOAD_RAMP <= t < h.release
            for h in self.plan.holds
            if h.release_kind != "throw"
        ):
            return np.zeros(len(times))
        p_obj = self._planned_object_positions(times)
        ahead = np.cos(yaw_ref) * (p_obj[:, 0] - p_ref[:, 0]) + np.sin(yaw_ref) * (
            p_obj[:, 1] - p_ref[:, 1]
        )
        return self.lean.angles(mass, ahead)

    def _lean_limited(self, t: float, dt: float, target: FloatArray) -> FloatArray:
        """The lean `target` (N + 1,) at t and the horizon's steps, followed no faster than
        LEAN_RATE from the lean in force at the last update (`_lean_now`, `_lean_t`).

        Why: leaning the trunk back takes a backward pitching moment from the feet, and its
        reaction pushes the hips and the centre of mass forward. Following the load's ramp
        (0 to 23 deg in 0.5 s for a 7.8 kg box), HECTOR's CoM went 7 cm ahead of its
        reference, onto its toes, the trunk sank 7 cm and the robot fell in the next turn
        (envelope seed 44021, walk-carry-024)."""
        if self.lean is None:
            return np.zeros(len(target))
        elapsed = max(0.0, t - self._lean_t) if math.isfinite(self._lean_t) else 0.0
        self._lean_t = t
        out = np.empty(len(target))
        prev = self._lean_now
        for i, goal in enumerate(target):
            step = LEAN_RATE * (elapsed if i == 0 else dt)
            prev = min(max(float(goal), prev - step), prev + step)
            out[i] = prev
        return out

    def _planned_object_accelerations(self, t: float, dt: float, n: int) -> FloatArray:
        """Planned acceleration (n, 3) of the held object at t + dt k, k = 1..n (m/s^2), by
        second differences of its planned path on the horizon's grid; zero where the stencil
        leaves the plan's hold window (before the grasp the path is not the object's).

        Why: a held object swung round the trunk in a loaded turn, or lifted, pushes the
        hands with -m_o a_o as well as its weight (the WBC's feed-forward already had it);
        the MPC's external force now has it too. Measured: envelope seed 5, 30 transfers,
        11 -> 14 succeed; with the carry clearance, seed 2026, 137 -> 150 of 200 (dynamic).
        Its cost: issue 12's walk-carry-6kg falls 1.0 s into its walk with it (and succeeds
        without it); where the planned path has kinks (segment joins) the second differences
        over the MPC's 30 ms steps are their largest, which is where to look next.

        Only points where the plan holds the object (lift-off to release: `Plan.object_held`,
        where `Plan.object_positions` is the object's) enter the stencil. It once took the
        hold window from the grasp and tested the times before the cache's rounding to the
        microsecond: a horizon point that fell on the release (every third update, the grid
        being t + 0.03 k with t on a 10 ms grid) was held for the test and the trunk's
        position for the cache, a 0.35 m jump: 393 m/s^2 at the release step, a fake push of
        some 300 N on the hands with the load then counted (envelope seed 22360,
        standing-hold-020, 7.6 kg: the first-step foot forces swung 100-400 N at 33 Hz while
        the block was set down, and the robot fell after the release)."""
        # On the microsecond grid of `_planned_object_positions`, so that the held test
        # below and the positions agree at the release's and the lift-off's instants.
        grid = np.rint((t + dt * np.arange(0, n + 2, dtype=np.float64)) * 1e6) * 1e-6
        p = self._planned_object_positions(grid)
        a = (p[2:] - 2.0 * p[1:-1] + p[:-2]) / (dt * dt)
        inside = self.plan.object_held(grid)
        a[~(inside[:-2] & inside[1:-1] & inside[2:])] = 0.0
        return a

    def _planned_object_positions(self, times: FloatArray) -> FloatArray:
        """`Plan.object_positions` (n, 3) along the planned trunk path, memoised per
        microsecond of `times` (evaluated at the rounded times, < 0.5 us off).

        Why: the plan evaluates the hand tracks point by point (about 10 us each), and an
        MPC update with a held load needs some 40 points (the horizon, the CoM shift 0.3 s
        ahead, now): 0.45 ms per update in scenarios/package-transfer.yaml. The horizon's
        times (t + 0.03 k, t on a 10 ms grid) come back every third update, so nearly every
        point is already known.

        A call that misses also evaluates the times the next OBJECT_PREFETCH MPC updates
        will ask for (the missed ones, one to OBJECT_PREFETCH MPC periods later): each call
        to the plan costs some 100 us before its first point, and without it nearly every
        update paid that for the two or three points at its horizon's end. The plan gives
        every time the same value whichever batch it comes in.

        The positions are kept as rows of one array, found by key (`_object_rows`), and a
        call whose times are all known is one gather: a list of 84 small arrays stacked
        cost 45-55 us inside the loop for the CoM shift's times, the gather a quarter."""
        keys = np.rint(np.asarray(times, dtype=float) * 1e6).astype(np.int64).tolist()
        rows = self._object_rows
        try:
            return self._object_store[[rows[k] for k in keys]]
        except KeyError:
            pass
        wanted = {k for k in keys if k not in rows}
        period = round(self.s.mpc_period * 1e6)
        ahead = {k + j * period for k in wanted for j in range(1, OBJECT_PREFETCH + 1)}
        missing = sorted(wanted | {k for k in ahead if k not in rows})
        pos = np.asarray(
            self.plan.object_positions(np.asarray(missing, dtype=float) * 1e-6), dtype=float
        )
        store = self._object_store
        if len(rows) + len(missing) > OBJECT_CACHE_SIZE:
            # Drop what lies in the past of the earliest time asked for now.
            oldest = min(keys)
            kept = [k for k in rows if k >= oldest]
            store = store[[rows[k] for k in kept]]
            rows = {k: i for i, k in enumerate(kept)}
        n = len(rows)
        if n + len(missing) > store.shape[0]:
            grown = np.empty((max(2 * store.shape[0], n + len(missing)), 3))
            grown[:n] = store[:n]
            store = grown
        store[n : n + len(missing)] = pos
        rows.update(zip(missing, range(n, n + len(missing)), strict=True))
        self._object_rows, self._object_store = rows, store
        return store[[rows[k] for k in keys]]

    def _update_load(self, t: float, hand_load: float | None) -> None:
        """Fold a measured hand load (N, vertical force the hands exert on held objects: wrist
        force sensors) into the load model: the load the controller uses at time t' is the
        plan's at t' plus today's offset of the measurement from the plan, within 0 and the
        mass of what the plan has in the hands.

        Why: the plan's load is a guess at when the weight comes on and goes off. An object
        that leaves its table later than planned (hands 2-3 cm lower than planned under the
        load), touches its support early while being lowered, or is still in the air at the
        planned release, made the MPC and the WBC push for a load that was not there (or
        forget one that was); those runs fell. With the measurement, the plan keeps its shape
        (the CoM shift still leads the load) but not its errors."""
        if hand_load is None:
            return
        raw = max(0.0, hand_load / GRAVITY)
        dt = max(0.0, t - self._load_t) if math.isfinite(self._load_t) else 0.0
        if self._load_filtered is None or not math.isfinite(self._load_t):
            self._load_filtered = raw
        else:
            a = dt / (LOAD_FILTER_TAU + dt)
            self._load_filtered += a * (raw - self._load_filtered)
        planned = self._planned_mass_at(t)
        top_now = self._hold_mass_at(t)
        estimate = self._load_filtered
        measured = min(estimate, top_now) if top_now > 0.0 else planned
        self._mass_now = measured
        self._supported = self._placing(t) and measured < SUPPORTED_LOAD * top_now
        # The load the CoM shift is computed for falls no faster than LOAD_RELEASE_DECAY: a
        # release drops the measured load at once, and a CoM reference that jumped forward by
        # the lean it had against the load tipped the robot onto its toes 0.2-0.4 s later
        # (pick-walk-drop). The MPC's force model takes the measured load as it is.
        fall = self._hold_mass / LOAD_RELEASE_DECAY * dt
        self._mass_shift = max(measured, self._mass_shift - fall)
        self._load_offset = measured - planned
        self._shift_offset = self._mass_shift - planned
        self._load_t = t

    def _grip_corrected(self, t: float, targets: FloatArray, p_hands: FloatArray) -> FloatArray:
        """Hand targets (2, 3) raised by how far above its planned point each hand closed on
        its object: the height error of the hand (measured, less the plan's target) when its
        contact starts, within `grasp_reach_limit` (the planner's tolerance for a grip point
        beyond the arms' reach), eased in (smoothstep) over LOAD_RAMP s from the hold's
        lift-off, while the contact lasts, and faded out (smoothstep, as
        `_released_pair_targets`) after it ends.

        Why: the grasp closes where the hands are, and a hand that cannot get down to a grip
        point at the edge of its reach closes higher on the box; the plan's hold then
        carries the box that much lower than it planned all the way to its target (envelope
        seed 46021, walk-carry-012: the hands stopped 3.7 cm above a grip point 1.9 cm
        beyond their reach, the box hung 3.4 cm lower than planned, its bottom level with
        the platform's top, the move over the platform pushed it into the platform's edge and
        it fell to the floor at the release). With the error added, the object follows its
        planned path and is set down where the plan puts it. Eased in only once the load is
        wholly on: added at the grip, it changed how heavy lifts loaded the robot (envelope
        seed 48021: transfer-052 in both strategies and dynamic transfer-037, 5.8-5.9 kg
        gripped 1-2.5 cm high, fell in the lift with it and not without); after the lift
        it raises the box during the carry, before any drop."""
        out = targets
        for k in range(2):
            on = self.plan.hand_contact(k, t)
            if on and not self._grip_on[k]:
                err = float(p_hands[k, 2] - targets[k, 2])
                self._grip_dz[k] = min(max(err, -self._grip_dz_max), self._grip_dz_max)
                self._grip_on[k] = True
                name = HAND_NAMES[k]
                lifts = [h.lift for h in self.plan.holds if name in h.hands and t < h.release]
                self._grip_lift[k] = min(lifts, default=math.inf)
            elif not on and self._grip_on[k]:
                self._grip_on[k] = False
                self._grip_off[k] = t
            dz = float(self._grip_dz[k])
            if dz == 0.0:
                continue
            end = t if on else float(self._grip_off[k])
            weight = smoothstep((end - float(self._grip_lift[k])) / LOAD_RAMP)
            if not on:
                u = (t - float(self._grip_off[k])) / self._pair_blend
                if u >= 1.0:
                    self._grip_dz[k] = 0.0
                    continue
                weight *= 1.0 - smoothstep(u)
            if out is targets:
                out = np.array(targets, dtype=float, copy=True)
            out[k, 2] += weight * dz
        return out

    def _released_pair_targets(self, t: float, targets: FloatArray) -> FloatArray:
        """Hand targets (2, 3) just after a two-hand release: the plan's, with the pair's
        separation at the release (`rigid_pair_targets`: the object's width) easing into the
        plan's (GRASP_SQUEEZE inside each side) over `_pair_blend` s (smoothstep).

        Why: at the release the targets went back at once to the plan's, 2-6 cm closer
        together than the hands stood on the object; in a throw that step came at the top of
        the hands' speed, both shoulder rolls jumped to 0.84 of their limit within 20 ms, the
        trunk was thrown 3 cm up and a foot came off the ground (envelope seed 16180,
        throw-000, 1.48 kg at 1.9 m/s: the robot fell 1.3 s later). The blend time is
        RELEASE_BLEND_TAU_RATIO time constants of the hands' Cartesian PD (1/sqrt(kp))."""
        t_r, offset = self._pair_release
        u = (t - t_r) / self._pair_blend
        if u >= 1.0:
            self._pair_release = (-math.inf, np.zeros(3))
            return targets
        fade = 1.0 - smoothstep(u)
        out = np.array(targets, dtype=float, copy=True)
        out[0] += 0.5 * fade * offset
        out[1] -= 0.5 * fade * offset
        return out

    def _placing(self, t: float) -> bool:
        """Whether a drop is putting a held object down at t (from the drop's start to its
        release): the only time the hands' guarded lowering applies (during a pick the
        measured load is low until the lift, and the guard would ratchet the hands up)."""
        return any(t0 <= t < t1 for t0, t1 in self._drop_windows)

    def _hold_window(self, t: FloatArray, extra: float) -> tuple[BoolArray, FloatArray]:
        """Whether the plan has an object between the hands at each time in t (from its grasp
        to `extra` s after its release) and the mass (kg) it then has there."""
        window = np.zeros(t.shape, dtype=bool)
        top = np.zeros(t.shape)
        for h in self.plan.holds:
            inside = (t >= h.grasp) & (t < h.release + extra)
            window |= inside
            top = np.where(inside, top + h.mass, top)
        return window, top

    def carried_mass(self, times: FloatArray) -> FloatArray:
        """Mass (kg) the MPC's force model takes the hands to carry at `times` (n,): the plan's
        load (`_planned_mass`) corrected by the measured hand load (`_update_load`) while the
        plan has an object between the hands (grasp to release)."""
        return self._corrected(times, self._load_offset, 0.0)

    def shift_mass(self, times: FloatArray) -> FloatArray:
        """Mass (kg) the held-load CoM shift is computed for at `times` (n,): as
        `carried_mass` while a load comes on (the plan's ramp after the lift-off, corrected by
        the measurement), but falling no faster than LOAD_RELEASE_DECAY allows, also for
        LOAD_RAMP_DOWN after the release. Once a held (not thrown) object's load is wholly on
        (LOAD_RAMP after its lift-off), the shift takes the measured load as it is now for
        every time ahead, until LOAD_RAMP_DOWN after the release: the load goes off when
        the object rests on its support, which the hand load measures, not on the plan's
        ramp-down.

        Why: the plan's ramp-down, led by LOAD_LEAD, took the lean away 0.3-0.9 s before the
        release while the hands still carried the whole load 0.3 m ahead; the combined CoM
        went over the toes and the robot fell forward as it placed the object (envelope seed
        4711: transfer-000, -004, -031, -045, 4.7-5.8 kg). Where the lean must go before the
        release, the lean weight says so (`_lean_weights`)."""
        out = self._corrected(times, self._shift_offset, LOAD_RAMP_DOWN)
        now = self._load_t
        if not math.isfinite(now):
            return out
        t = np.asarray(times, dtype=float)
        for h in self.plan.holds:
            if h.release_kind == "throw":
                continue
            if h.lift + LOAD_RAMP <= now < h.release + LOAD_RAMP_DOWN:
                out = np.where(t >= h.grasp, self._mass_shift, out)
        return out

    def _corrected(self, times: FloatArray, offset: float, extra: float) -> FloatArray:
        planned = self._planned_mass(times)
        if offset == 0.0:
            return planned
        t = np.asarray(times, dtype=float)
        window, top = self._hold_window(t, extra)
        corrected = np.clip(planned + offset, 0.0, top)
        return np.where(window, corrected, planned)

    def _planned_mass_at(self, t: float) -> float:
        """Scalar `_planned_mass` (the per-tick path: no arrays)."""
        out = 0.0
        for h in self.plan.holds:
            frac = smoothstep((t - h.lift) / LOAD_RAMP)
            if math.isfinite(h.release):
                if h.release_kind == "throw":
                    frac = frac if t < h.release else 0.0
                else:
                    frac *= smoothstep((h.release - t) / LOAD_RAMP_DOWN)
            out += h.mass * frac
        return out

    def _lift_mass(self, t: float, mass_now: float) -> float:
        """Mass (kg) the WBC's object feed-forward (`_object_generalized_force`) takes at t:
        the load measured now (`mass_now`), but, for a hold after whose lift-off a foot steps
        within LOAD_RAMP (`_steps_after_lift`), at least its object's whole mass from the
        planned lift-off until LOAD_RAMP after it (or its release), eased in over the grip
        (smoothstep from the hands' contact to the lift-off).

        Why: the measured load is what the hands already carry, so while the box still rests
        on its table it is near zero, and the hands had to build the lifting force from their
        tracking error while their raise ran on. A 7.97 kg box left its table 0.18 s after the
        planned lift-off (envelope seed 58021, walk-carry-019); the hands then whipped it in
        at 0.5 m/s to catch up with their path, in the raise's slowing half, where the MPC's
        object model (the plan's accelerations) had the reaction the other way; the trunk ran
        12.9 cm towards the box at up to 0.53 m/s, the combined centre of mass passed the
        toes, the MPC's first-step vertical force fell to 23-200 N and the robot fell in the
        turn that followed. With the weight fed forward the box leaves 0.13 s after the
        lift-off (the rest is the hands' tracking of the raise under the load) and the
        trunk moves 1.7 cm. The plan lifts the object at its lift-off, so the hands lift it
        then; nothing here is tuned (the grip's span and LOAD_RAMP are the plan's and the
        load model's). Measured: of the 44 runs that failed on envelope seeds 53021-58021,
        33 succeed with it against 8 without (+25 -0); fresh seed 60021 397 of 400 against
        396 (README, Envelope). A grasp that fails (the hands miss the object) gets the
        weight fed forward to empty hands until the window ends: such runs fail anyway.

        Why only where a foot steps soon: standing, the table sharing the weight while the
        hands' force builds is the gentler transfer, and the lean follows the measured load
        as it comes. Fed forward there too, the repository's 14 kg standing hold lifted its
        block at once, before the lean had caught up with it; the trunk lurched 9 cm forward,
        sank 7 cm and set the block back on its table. Where a foot steps within LOAD_RAMP
        the lean is in place before the lift-off (`_pre_lean`) and the pull-in must be done
        before the step.

        For a heavy object held standing whose pick the planner gave the time
        (`ObjectHold.slow_lift`), the measured load is fed forward at most as far as the
        plan's load ramp has come (the object's mass times the smoothstep over LOAD_RAMP from
        the lift-off that `_planned_mass` and the CoM shift plan with).
        Why: feeding the measurement forward is a positive feedback (the hands push up, the
        wrists measure more, more is fed forward), which took an 11.39 kg block's weight in
        0.1 s, where leaning 7 cm back with the centre of pressure inside the feet takes
        about 0.6 s (`_pre_lean_window`'s T); the robot's CoM stopped 4.6 cm behind its
        ankles with the feet's centre of pressure at the toes, the trunk sank 5 cm and the
        block went back onto its table (HECTOR envelope seed 92021, standing-hold-008, both
        strategies, after the planner's 2 cm step nearer). Capped, the weight comes on over
        0.4 s (the hands' raise adds to the ramp), the lean follows and the block is held.
        Only there: capped on every standing pick, 2-3 kg boxes picked in 1 s were still on
        their tables at the pick's end (HECTOR seed 91021, standing-hold-001, -007); light
        loads need little lean, and heavy standing picks last HEAVY_PICK_MIN or more."""
        out = mass_now
        for h in self._slow_lifts:
            if h.lift <= t < min(h.lift + LOAD_RAMP, h.release):
                out = min(out, h.mass * smoothstep((t - h.lift) / LOAD_RAMP))
        for h in self._on_time_lifts:
            if not (h.grasp <= t < min(h.lift + LOAD_RAMP, h.release)):
                continue
            span = h.lift - h.grasp
            u = 1.0 if span <= 0.0 else (t - h.grasp) / span
            out = max(out, h.mass * smoothstep(u))
        return out

    def _hold_mass_at(self, t: float) -> float:
        """Mass (kg) of what the plan has between the hands at t (grasp to release), 0 if
        nothing."""
        return sum(h.mass for h in self.plan.holds if h.grasp <= t < h.release)

    def _planned_mass(self, times: FloatArray) -> FloatArray:
        """Mass (kg) the plan has the hands carry at `times` (n,): each held object's mass times a
        load
        fraction that rises smoothly over LOAD_RAMP after the planned lift-off and falls over
        LOAD_RAMP_DOWN before a drop's release (a throw lets go at once).

        Why a ramp rather than the plan's 0/1 sigma_e: a step in the load makes the CoM
        reference jump back by m_o d / (m + m_o) (11 cm for 8 kg). The MPC answered such a jump
        with a first-step vertical force far below the weight followed by large ones (it buys
        friction for a big backward Fx); re-planning every 10 ms applies only that first step,
        so the robot sagged 7 cm and dropped the load. Lifting transfers the weight gradually
        in reality too: the hands take it as they pull up."""
        t = np.asarray(times, dtype=float)
        out = np.zeros(t.shape)
        for h in self.plan.holds:
            frac = smoothstep_array((t - h.lift) / LOAD_RAMP)
            if math.isfinite(h.release):
                if h.release_kind == "throw":
                    frac = np.where(t < h.release, frac, 0.0)
                else:
                    frac = frac * smoothstep_array((h.release - t) / LOAD_RAMP_DOWN)
            out += h.mass * frac
        return out

    def _com_shift(
        self,
        t_lead: FloatArray,
        mass: FloatArray,
        p_com: FloatArray,
        support: tuple[FloatArray, FloatArray] | None = None,
        standing: BoolArray | None = None,
    ) -> FloatArray:
        """CoM reference shift (n, 2) for held loads: the robot's CoM moves away from the
        object by the share `_lean_share` of s = m_o d / (m + m_o), the shift that would put
        the combined CoM of robot and object where the robot's own CoM stands unloaded
        ((m p_c + m_o p_o) = (m + m_o) p with p_o = p_c + d gives p_c = p - s). Without it the
        MPC, which sees only 0.6 s ahead, does not find the backward lean a held load needs
        (shared/controller-notes.md).

        The shift leads the load by LOAD_LEAD: with the CoM still over the feet when an 8 kg
        load 0.35 m ahead comes on, its pitch torque (27 N m) exceeds what the line feet can
        answer (toe-loaded CoP, 0.09 m x 245 N = 22 N m), and moving the CoM back then needs a
        backward push whose own pitch torque makes it worse. So the robot starts leaning back
        (onto its heels, which is feasible without the load) just before the weight comes on.

        The object's offset d is the larger of where it is planned at the lead time and at the
        time concerned: the lean leads a load that comes on or goes out, but lags one that
        comes in. Why: a pick lifts the object where it stood (0.3-0.35 m out) and then pulls
        it in; with d at the lead time only, the lean was already the one for the pulled-in
        object while the hands held it at the lift point, and the combined CoM stood on the
        toes (0.0-0.4 cm inside) for 5.8-7.9 kg (envelope seed 16180, walk-carry-000, -002,
        -013: fell). Measured on the manipulation scripts of seeds 4711 and 5000 (276
        accepted): 253 -> 255 succeed (walk-carry +4 -3, transfer +2, hold -1); seed
        16180: 112 -> 113 of the 120 run at both revisions (walk-carry +2, side-carry -1).

        Where a hold leans before its lift-off (`_pre_lean`), the larger of the two shifts
        counts.

        Where the feet stand (`support`), the shift is taken from where they are, not from
        where the plan put them: the whole shift (lean weight 1) leaves the robot's own CoM
        the load's shift s behind its nominal place over the feet, i.e. s plus how far the
        reference stands ahead of that place along the load's direction (the offset's
        excess over the nominal one, `_support_offset`; the equal-margin share, weight 0,
        already counts the offset: `_lean_share`), and the pre-lift lean likewise
        (`_pre_lean`). Why: a turn in place or a walk can leave the feet centimetres off
        the plan while the reference stays the plan's; the shift from the plan then centred
        the combined CoM that far off the feet (HECTOR envelope seed 83021, dynamic
        transfer-005: the robot stood 5 cm behind its plan after a 110 deg turn, the 5.48 kg
        parcel came on with the combined CoM 0.5 cm inside the toes, the MPC cut the
        vertical force to f_min to keep the pitch, the trunk sank 10 cm and the parcel went
        back onto its table).

        From the lead times t_lead (n,) (the times concerned + LOAD_LEAD), the carried mass
        there (n,) kg and the CoM reference there (n, 3) m; `support` is (p, hull) where both
        feet stand: the CoM reference now (2,) and the feet's support polygon; `standing`
        (n,) marks the rows the feet still stand as they do now (None: all of them; the
        others take the nominal offset)."""
        both = self._planned_object_positions(
            self._held_times(np.concatenate([t_lead, t_lead - LOAD_LEAD]))
        )
        size, unit = reference_kernels.load_shift(
            both,
            np.ascontiguousarray(p_com, dtype=np.float64),
            np.ascontiguousarray(mass, dtype=np.float64),
            float(self.mass),
        )
        weights = self._lean_weights(t_lead)
        offset = self._offsets(support, standing, unit)
        along = self._lean_share(size, weights, offset) * size
        if offset is not None:
            along = np.maximum(along + weights * (offset - self._support_offset), 0.0)
        pre = self._pre_lean(t_lead - LOAD_LEAD, p_com, support, standing)
        return reference_kernels.larger_shift(
            np.ascontiguousarray(along, dtype=np.float64), unit, pre
        )

    def _offsets(
        self,
        support: tuple[FloatArray, FloatArray] | None,
        standing: BoolArray | None,
        unit: FloatArray,
    ) -> FloatArray | None:
        """How far (n,) m the reference `support[0]` stands ahead of the middle of the feet's
        polygon `support[1]` along each unit direction `unit` (n, 2) (`chord_offsets`), the
        nominal `_support_offset` where that is undefined (outside the polygon, no direction)
        or the feet no longer stand as they do (`standing` False); None without `support`."""
        if support is None:
            return None
        offset = chord_offsets(support[0], unit, support[1])
        if standing is not None:
            offset = np.where(standing, offset, np.nan)
        return np.where(np.isfinite(offset), offset, self._support_offset)

    def _pre_lean(
        self,
        t: FloatArray,
        p_com: FloatArray,
        support: tuple[FloatArray, FloatArray] | None = None,
        standing: BoolArray | None = None,
    ) -> FloatArray:
        """CoM reference shift (n, 2) at the times t (n,) that has each hold's equal-margin
        share of the load shift (`_lean_share` with weight 0) in place by its planned lift-off,
        for the object where it is gripped then (from the CoM reference p_com (n, 3)),
        capped at the hold's `pre_lean` (the room the arms' reach leaves at the grasp, from
        the plan); with `support` and `standing` (`_com_shift`), the share for the feet as
        they stand. It eases in over `_pre_lean_windows` before the lift-off and stays until
        LOAD_RAMP after it, where the measured load has taken over (`shift_mass`);
        `_com_shift` takes it where it is the larger. It stays the lean for the object where
        it was lifted while the hands pull it in: with the offsets the shift counts after the
        lift-off (the pulled-in object's), seed 22360's walk-carry-015 and -017 (below) fell
        again.

        Why: the load ramp and its LOAD_LEAD leave the lean at about a tenth of the shift at
        the lift-off, but the box leaves its table within 0.1-0.2 s of it. The measured load
        then pulled the lean back 4-5 cm in one step; the MPC answered with a first-step
        vertical force near f_min (it buys the friction for a large backward push over the
        next steps), the trunk sank 5 cm, the combined CoM passed the toes, and the turn that
        followed walked the robot forward off its reference until a hip saturated (envelope
        seed 22360: walk-carry-000, -015, -017, 6.2-7.75 kg, fell in the turn after the pick;
        with the lean in place all three place their box)."""
        out = np.zeros((len(t), 2))
        for h, t0, t1, p_o in self._pre_lean_windows:
            inside = (t >= t0) & (t < h.lift + LOAD_RAMP)
            if not inside.any():
                continue
            s = (h.mass / (self.mass + h.mass)) * (p_o[None, :] - p_com[:, :2])
            size = np.linalg.norm(s, axis=1)
            with np.errstate(divide="ignore", invalid="ignore"):
                unit = np.where(size[:, None] > 1e-9, s / size[:, None], 0.0)
            offset = self._offsets(support, standing, unit)
            x = np.minimum(self._lean_share(size, np.zeros(len(t)), offset) * size, h.pre_lean)
            ramp = np.where(inside, smoothstep_array((t - t0) / (t1 - t0)), 0.0)
            out -= (ramp * x)[:, None] * unit
        return out

    def _leans_before_lift(self, hold: ObjectHold) -> bool:
        """Whether `hold` gets the pre-lift lean (`_pre_lean`): the arms leave it room
        (`ObjectHold.pre_lean` > 0) and a foot steps within LOAD_RAMP of its lift-off (the
        plan's contact schedule, on a 10 ms grid), before the measured-load lean has come on.

        Why only then: the falls it answers all came in the first steps after the pick (a
        turn or walk started while the lean still followed the load); standing, the lean
        catches up with the measured load as before. Leaning early where nothing steps lost
        two of the repository's checks and gained nothing: the 10 kg standing hold sank 5 cm
        half a second after its lift (the block went back onto its table), and the heavy fast
        throw's hop after the release landed the feet together."""
        return hold.pre_lean > 0.0 and self._steps_after_lift(hold)

    def _steps_after_lift(self, hold: ObjectHold) -> bool:
        """Whether a foot steps within LOAD_RAMP of `hold`'s lift-off (the plan's contact
        schedule, on a 10 ms grid)."""
        times = hold.lift + np.arange(0.0, LOAD_RAMP + 1e-9, 0.01)
        return not bool(np.all(self.plan.contact_flags(times)))

    def _pre_lean_window(self, hold: ObjectHold) -> tuple[float, float]:
        """When (s) the pre-lift lean of `hold` (`_pre_lean`) starts and is complete: it
        ends at the lift-off and takes T = sqrt(6 x z / (g l)) for a lean of x =
        `hold.pre_lean` (its cap), the CoM height z and half the feet's support length l
        (robot.yaml's toe and heel): a smoothstep over T peaks at 6 x / T^2, the CoM
        acceleration that puts the zero-moment point l from the CoM, so the lean never asks
        the feet for a centre of pressure beyond their support. It starts at 0 at the
        earliest (then it is quicker)."""
        half = 0.5 * (self.desc.foot_toe + self.desc.foot_heel)
        T = math.sqrt(6.0 * hold.pre_lean * self.com_height / (GRAVITY * half))
        t0 = max(hold.lift - T, 0.0)
        return t0, max(hold.lift, t0 + 1e-3)

    def _lean_share(
        self, size: FloatArray, weight: FloatArray, offset: FloatArray | None = None
    ) -> FloatArray:
        """Share (n,) of the full load shift of size `size` (n,) m that the CoM reference
        takes, for the lean weights `weight` (n,) (`_lean_weights`): the equal-margin share
        beta plus `weight` of the rest, beta + w (1 - beta).

        Why not always the whole s: the load is not on the robot at every instant the plan
        says it is. It comes onto the hands as the object is lifted (later when the arms lag
        their path), goes off within 0.1-0.3 s of the object touching its support, and the
        measured hand load chatters +-30 %. With the whole s the robot's own CoM stands s
        behind its nominal place: 7-11 cm for 5-8 kg held 0.3-0.37 m ahead, behind the heels
        (6 cm behind the sole site), so it is balanced only while the whole load is on; robots
        fell backwards when the load came late at a pick or went early at a drop (envelope
        seed 11: walk-carry-009, 7.6 kg; transfers after their release). Since the shift
        counts the measured load (`shift_mass`), the whole s stands while the load is held
        and the equal-margin share only where the load comes on or goes off
        (`_lean_weights`, `_pre_lean`).

        The equal-margin share: along the feet (line feet: support from `heel` behind to `toe`
        ahead of the sole site, robot.yaml), the robot's own CoM stands `c` ahead of the sole
        site at the nominal pose. Leaning back by beta s leaves the unloaded robot's CoM
        c - beta s ahead of the sole site, heel margin h + c - beta s; the loaded combined CoM
        is (1 - beta) s further forward, toe margin t - c - (1 - beta) s. Equal margins:
        beta = 1/2 + (c - (t - h)/2) / s, clipped to [0, 1]. For HECTOR c = 0.015 m is the
        support's middle, so beta = 1/2 for every load: both margins are (t + h - s) / 2.

        `offset` (n,) m, where given, replaces c - (t - h) / 2, the nominal CoM's offset from
        the middle of the support: while both feet stand it is measured on the feet as they
        landed (`_com_shift`), how far the standing reference stands ahead of the middle of
        the support polygon's chord along the load's direction. Why: a walk's last step
        lands by the capture point, 1-8 cm from its plan, and the reference stays the plan's;
        the nominal share then left the unloaded robot's CoM behind the heels of feet that
        had landed ahead of it (HECTOR envelope seed 72021, walk-carry-007, 6.42 kg: right
        foot 4.8 cm and left 1.3 cm ahead of the plan, CoM reference 0.1 cm inside the hull's
        back edge after the lean, fall backwards 0.6 s after the release, both strategies)."""
        beta = equal_margin_share(size, self._support_offset if offset is None else offset)
        return beta + np.asarray(weight, dtype=float) * (1.0 - beta)

    def _lean_weights(self, t_lead: FloatArray) -> FloatArray:
        """Weight (n,) of the rest of the held-load lean beyond its equal-margin share at the
        lead times t_lead (n,) (`_lean_share`): 1, the whole shift that centres robot and
        load over the feet, except before a drop's release, where it eases to 0 over
        LOAD_RAMP_DOWN (smoothstep) and stays 0 until LOAD_RAMP_DOWN after it (the window
        in which the shift still counts that load, as `shift_mass`), so that the lean is
        the equal-margin share when the load goes off: the whole shift (9-10 cm for 7.6 kg
        0.34 m ahead) left the unloaded robot's CoM behind its heels, while the equal share
        leaves it as far inside the heels as the loaded combined CoM is inside the toes.

        Why the whole shift while the load is held, for every load: the shift counts the
        load the hands measure (`shift_mass`), so a load that comes on late does not lean
        the robot back before it is there, and the equal-margin share (half the shift on
        HECTOR) left a 5-6 kg parcel's combined CoM 1-3 cm inside the toes. The load comes
        off the table within 40-60 ms of the hands taking it, 0.15 s after the planned
        lift-off, and the hands pull it in at up to 0.55 m/s: its momentum's reaction ran
        the robot's CoM forward at 0.2-0.75 m/s in every heavy transfer looked at (envelope
        seed 50021: transfer-001, -004, -012, -014, -029, -033, -042, -045; the momenta of
        robot and parcel from the logged joint positions, the ground's forward force under
        20 N), with no toe margin left to stop it; where a turn's step came before the lurch
        was caught, the robot walked off its reference into the table and fell. Until
        2026-12-05 a plan-chosen weight (0 up to a third of the torque limits' static ratio,
        1 from two thirds) gave light and medium loads the equal share. Measured on the
        heavy scripts of seeds 46021, 48021, 49021 and 50021 (69 transfers of 4.5 kg and
        more, 26 walk-carries of 6.5 kg and more, 40 standing holds of 9 kg and more,
        dynamic): 120 -> 125 of 135 succeed (+9 -4; every standing hold both ways); on the
        whole envelope of fresh seed 51021: see the README."""
        t = np.asarray(t_lead, dtype=float)
        out = np.full(t.shape, -1.0)
        for h in self.plan.holds:
            inside = (t >= h.grasp) & (t < h.release + LOAD_RAMP_DOWN)
            w = np.ones(t.shape)
            if h.release_kind == "drop" and math.isfinite(h.release):
                w = smoothstep_array((h.release - t) / LOAD_RAMP_DOWN)
            out = np.where(inside, np.maximum(out, w), out)
        return np.where(out < 0.0, 1.0, out)

    def _held_times(self, t_lead: FloatArray) -> FloatArray:
        """Lead times (n,) at which to take the held object's planned position for the CoM
        shift: a lead time past a drop's release, while the shift still counts that object
        (LOAD_LEAD + LOAD_RAMP_DOWN after it), is moved back to just before the release. Past
        it the plan has no object between the hands (object_positions gives the trunk), and
        the shift for what load remained vanished LOAD_LEAD before the release: the CoM
        reference jumped forward with part of the load still in the hands (envelope seed 11,
        transfer-008)."""
        out = np.array(t_lead, dtype=float)
        for h in self.plan.holds:
            if h.release_kind != "drop" or not math.isfinite(h.release):
                continue
            late = (out >= h.release) & (out < h.release + LOAD_LEAD + LOAD_RAMP_DOWN)
            out[late] = h.release - 1e-4
        return out

    # -- the tick ------------------------------------------------------------------------------
    def step(
        self, t: float, q: FloatArray, v: FloatArray, hand_load: float | None = None
    ) -> ControlOutput:
        """Torques (n,) for state (q (7 + n,), v (6 + n,), pinocchio convention) at time t (s)
        for the robot's n joints;
        `hand_load` (N) is the measured vertical force the hands exert on what they hold
        (None: no sensor, the plan's load alone)."""
        t_dyn = time.perf_counter()
        r = self.robot
        q = np.ascontiguousarray(q, dtype=np.float64)
        v = np.ascontiguousarray(v, dtype=np.float64)
        r.update(q, v)
        R = pin_base_rotation(q)
        roll, pitch, yaw = rpy_from_matrix(R)
        omega_w = R.dot(v[3:6])
        p_c = r.com_position
        v_c = r.com_velocity
        # Feet (0, 1), hands (2, 3) and trunk (4), stacked.
        p_fr, R_fr, J_fr, dJv_fr = r.frames_kinematics(self._frames)
        v_fr = J_fr.dot(v)
        p_feet, R_feet, J_feet, dJv_feet = p_fr[:2], R_fr[:2], J_fr[:2], dJv_fr[:2]
        v_feet = v_fr[:2]
        yaw_feet = np.arctan2(R_feet[:, 1, 0], R_feet[:, 0, 0])
        M, h = r.M, r.h
        dyn_time = time.perf_counter() - t_dyn

        plan = self.plan
        ref = plan.trunk_reference_at(t)
        self._update_load(t, hand_load)
        mpc_due = t - self._last_mpc_t >= self.s.mpc_period - 1e-9
        if mpc_due and self.s.recovery_steps:
            self._add_steps(t, p_c, v_c, p_feet, yaw_feet, float(ref.yaw))
        stance = (
            bool(plan.foot_stance(0, t)) and self.recovery.swinging(0, t) is None,
            bool(plan.foot_stance(1, t)) and self.recovery.swinging(1, t) is None,
        )
        # The load now, for the MPC and the WBC's object feed-forward: with a measurement,
        # `_update_load` has it (carried_mass at t itself, without the arrays).
        mass_now = (
            self._mass_now if hand_load is not None else float(self.carried_mass(np.array([t]))[0])
        )
        # Swing bookkeeping: remember where each swing started.
        for k in range(2):
            if not stance[k] and self._last_contact[k]:
                sw = self._swing[k]
                sw.t_liftoff = t
                sw.p_start = p_feet[k].copy()
                sw.yaw_start = float(yaw_feet[k])
        contact_changed = stance != self._last_contact
        self._last_contact = stance

        # MPC.
        mpc_sol: MpcSolution | None = None
        mpc_time = 0.0
        if contact_changed or mpc_due:
            yaw_ref_now = float(ref.yaw)
            yaw_meas = yaw_ref_now + wrap_angle(yaw - yaw_ref_now)
            x0 = np.concatenate([[roll, pitch, yaw_meas], p_c, omega_w, v_c, [0, 0, -GRAVITY]])
            t_m = time.perf_counter()
            p_hands_mid = 0.5 * (p_fr[2] + p_fr[3])
            mpc_sol = self._run_mpc(t, x0, p_c, v_c, p_feet, yaw_feet, p_hands_mid, mass_now)
            mpc_time = time.perf_counter() - t_m
            if not mpc_sol.ok and self._last_mpc is None:
                raise SolverFailure(t, "mpc", self.s.qp_backend, mpc_sol.status)
            self._last_mpc = mpc_sol
            self._last_mpc_t = t
        assert self._last_mpc is not None
        wrench = np.zeros((2, 6))
        for k in range(2):
            if stance[k]:
                wrench[k, :3] = self._last_mpc.forces_world[k]
                wrench[k, 3:] = self._last_mpc.moments_world[k]

        # Swing-foot targets: position, velocity, acceleration rows and yaw per swinging foot.
        foot_targets = np.full((2, 3), np.nan)
        foot_yaw_targets = np.full(2, np.nan)
        swing_pva = np.zeros((2, 3, 3))
        swing_yaw = np.zeros(2)
        n_swing = 0
        for k in range(2):
            if stance[k]:
                continue
            added = self.recovery.swinging(k, t)
            ph = plan.swing_phase(k, t)
            if added is not None:
                liftoff, touchdown = added.liftoff, added.touchdown
                p_td, yaw_td = added.target, added.yaw
            elif ph is not None:
                liftoff, touchdown = ph.liftoff, ph.touchdown
                key = (k, ph.touchdown)
                if key not in self._footholds:
                    self._footholds[key] = self._foothold(k, t, ph.touchdown, p_c, v_c)
                p_td, yaw_td = self._footholds[key]
            else:
                continue
            sw = self._swing[k]
            duration = touchdown - liftoff
            phase = min(1.0, max(0.0, (t - liftoff) / duration))
            pt = swing_point(sw.p_start, p_td, self.s.swing_height, phase, duration)
            sb, _, _ = min_jerk(phase)
            yaw_des = sw.yaw_start + sb * wrap_angle(yaw_td - sw.yaw_start)
            foot_targets[k] = pt.position
            foot_yaw_targets[k] = yaw_des
            swing_pva[n_swing] = (pt.position, pt.velocity, pt.acceleration)
            swing_yaw[n_swing] = yaw_des
            n_swing += 1
        # Hand targets.
        v_base, yaw_rate = R.dot(v[:3]), float(omega_w[2])
        hand_targets, v_hand_des = plan.hand_target_arrays(t, q[:3], yaw, v_base, yaw_rate)
        J_hands = np.ascontiguousarray(J_fr[2:4, :3])
        p_hands = p_fr[2:4]
        hand_targets = self._grip_corrected(t, hand_targets, p_hands)
        v_hands = v_fr[2:4, :3]
        if self._supported:
            # Guarded lowering: once what the hands hold rests on something (the measured load
            # is under SUPPORTED_LOAD of its mass), they stop pushing it further down, and
            # they stop pushing it sideways: they hold where they are (damped). The support
            # anchors the object by friction, so a hand still tracking its planned point then
            # pushes the trunk instead of the object: a 7.6 kg box set on a platform drew the
            # trunk 4 cm back in the 0.2 s before its release and the robot fell backwards
            # after it (envelope seed 4711, walk-carry-003).
            hand_targets, v_hand_des = hand_targets.copy(), v_hand_des.copy()
            for k in plan.holding_hands(t):
                if hand_targets[k, 2] < p_hands[k, 2]:
                    hand_targets[k, 2] = p_hands[k, 2]
                    v_hand_des[k, 2] = max(0.0, float(v_hand_des[k, 2]))
                hand_targets[k, :2] = p_hands[k, :2]
                v_hand_des[k, :2] = 0.0
        if len(plan.holding_hands(t)) == 2:
            gap = hand_targets[0] - hand_targets[1]
            hand_targets = rigid_pair_targets(hand_targets, p_hands)
            v_hand_des = rigid_pair_velocities(v_hand_des, gap)
            self._pair_release = (t, hand_targets[0] - hand_targets[1] - gap)
        elif math.isfinite(self._pair_release[0]):
            hand_targets = self._released_pair_targets(t, hand_targets)
        fed = self._hand_gains(t)
        hand_acc = self._hand_kp * (hand_targets - p_hands)
        if fed:
            a_ff = plan.hand_target_accelerations(t, q[:3], yaw, v_base, yaw_rate)
            hand_acc = self._hand_ff * a_ff + hand_acc
        hand_acc = hand_acc + self._hand_kd * (v_hand_des - v_hands)
        tau_ext = self._object_generalized_force(t, self._lift_mass(t, mass_now), J_hands, hand_acc)

        t_w = time.perf_counter()
        wbc_out: WbcOutput | None = None
        if self.s.mapping == "jacobian":
            tau = self._jacobian_mapping(
                stance,
                wrench,
                J_feet,
                v_feet,
                p_feet,
                R_feet,
                swing_pva[:n_swing],
                swing_yaw[:n_swing],
                J_hands,
                p_hands,
                v_hands,
                hand_targets,
                v_hand_des,
                tau_ext,
                q,
                v,
            )
        else:
            p_des = np.asarray(ref.position, dtype=float).copy()
            p_des[:2] += self._shift_now + self._stand_offset
            J_t, b_t, a_t, ends = stack_tasks(
                self._gains,
                q,
                v,
                R,
                omega_w,
                p_des,
                np.asarray(ref.velocity, dtype=float),
                float(ref.yaw),
                -self._lean_now,
                float(ref.yaw_rate),
                J_fr[4],
                dJv_fr[4],
                np.array(stance, dtype=np.bool_),
                J_feet,
                dJv_feet,
                v_feet,
                p_feet,
                R_feet,
                n_swing,
                swing_pva,
                swing_yaw,
                J_hands,
                np.ascontiguousarray(dJv_fr[2:4, :3]),
                hand_acc,
            )
            if len(self._cols_wall):
                J_t, qdd_cmd = self._keep_in_working_range(J_t, b_t, a_t, ends, q, v)
            else:
                qdd_cmd = prioritized_rows(J_t, a_t - b_t, ends)
            if len(self._cols_posture):
                # Lowest priority: the posture of the joints no task above determines.
                a_p = posture_acceleration(
                    self._cols_posture,
                    self._q_posture,
                    q,
                    v,
                    self.s.posture_kp_acc,
                    self.s.posture_kd_acc,
                )
                qdd_cmd = qdd_cmd + posture_in_null_space(J_t, self._cols_posture, a_p, qdd_cmd)
            idx = [k for k in range(2) if stance[k]]
            w5 = np.zeros(5 * len(idx))
            for i, k in enumerate(idx):
                w5[5 * i : 5 * i + 5] = wrench_world_to_w5(float(yaw_feet[k]), wrench[k])
            if len(idx) == 2:
                # Both feet: the arrays as they are (J_feet's rows stacked are a view).
                Jc, yaw_c = J_feet.reshape(-1, J_feet.shape[2]), yaw_feet
            else:
                Jc, yaw_c = J_feet[idx].reshape(-1, J_feet.shape[2]), yaw_feet[idx]
            wbc_out = self.wbc.solve_arrays(M, h, qdd_cmd, Jc, yaw_c, w5, tau_ext)
            tau = wbc_out.tau
        wbc_time = time.perf_counter() - t_w
        # (np.minimum / np.maximum: np.clip costs several times more on a few values.)
        tau_clipped = np.minimum(np.maximum(tau, self._neg_tau_limits), self.tau_limits)
        # A torque at its limit to rounding (a QP's active bound) is not a clip.
        n_clipped = int(np.count_nonzero(np.abs(tau) > self._clip_limits))
        return ControlOutput(
            tau=tau,
            tau_clipped=tau_clipped,
            n_clipped=n_clipped,
            wrench_world=wrench,
            stance=stance,
            foot_targets=foot_targets,
            foot_yaw_targets=foot_yaw_targets,
            hand_targets=hand_targets,
            mpc=mpc_sol,
            mpc_time_s=mpc_time,
            wbc=wbc_out,
            wbc_time_s=wbc_time,
            dynamics_time_s=dyn_time,
        )

    # -- pieces ---------------------------------------------------------------------------------
    def _hand_gains(self, t: float) -> bool:
        """Set each hand's PD gains and feed-forward share for time t: on its way to a grasp
        (a segment in APPROACH_LABELS), on a robot with approach gains (robot.yaml
        `hand_approach_kp`: kp, critically damped), those with the target's acceleration fed
        forward; otherwise `ControllerSettings.hand_kp_acc` / `hand_kd_acc` and no
        feed-forward. Returns whether some hand is fed forward now.

        Why, on H1: the WBC QP relaxes the floating base's accelerations, not the joints', so
        whatever the trunk's rotation misses of its command the hands inherit through the arm,
        times the lever to the hand. At kp 400 H1's hands were 3-5 cm inward of their reach
        while the trunk turned at 60 deg/s in steps (yaw bursts of 140 deg/s) and struck the
        parcel they were going round (envelope seed 42013, transfer-044 and -053: pushed 7 cm
        along the table, not grasped); at the trunk's attitude bandwidth (kp 1500) with the
        feed-forward, within 1-1.5 cm, both placed. Why not on HECTOR: its arms are half as
        long, and the same approach made 4 of seed 16339's 400 runs fall or miss that stood
        without it (transfer-007 and walk-carry-024, both strategies). Why not while holding:
        a held object's planned acceleration fed forward through the hands reaches the WBC
        as its inertia (`_object_generalized_force`) at the plan's times instead of as the
        hands follow; a 7.57 kg box turned with right after its pick then fell HECTOR at
        2.7 s (seed 16339, quasi-static walk-carry-024)."""
        fast = self._approach_gains
        if fast is None:
            return False
        tracks = self.plan.manipulation.tracks
        any_fast = False
        for k in range(2):
            kp, kd, ff = self.s.hand_kp_acc, self.s.hand_kd_acc, 0.0
            if tracks[k].label_at(t) in APPROACH_LABELS:
                kp, kd, ff = fast[0], fast[1], 1.0
                any_fast = True
            self._hand_kp[k, 0] = kp
            self._hand_kd[k, 0] = kd
            self._hand_ff[k, 0] = ff
        return any_fast

    def _object_generalized_force(
        self, t: float, mass: float, J_hands: FloatArray, hand_acc: FloatArray
    ) -> FloatArray:
        """J_e' F_ext (nv,): what the held object of `mass` (kg, the carried mass at t) does to
        the holding hands (J_hands (2, 3, nv) linear Jacobians), shared equally: its weight
        and its inertia at the hands' commanded accelerations (2, 3),
        F_hand = (m_o / n) (g - a_hand). The pinocchio model does not contain the object, so
        without the inertial part the hand tasks act as if the hands were empty and lag a
        heavy load."""
        tau_ext = np.zeros(J_hands.shape[2])
        if mass <= 0.0:
            return tau_ext
        hands = self.plan.holding_hands(t)
        if not hands:
            return tau_ext
        # A rigid object held at the hand points moves with their mean; the hands' difference
        # (the squeeze) only makes internal force and must not be fed forward as inertia.
        # (The mean as np.mean forms it, the sum over the hands over their number, without
        # building an array of the rows first.)
        a_obj = hand_acc[hands[0]]
        for k in hands[1:]:
            a_obj = a_obj + hand_acc[k]
        a_obj = a_obj / len(hands)
        f = mass / len(hands) * (_GRAVITY_VECTOR - a_obj)
        for k in hands:
            tau_ext += J_hands[k].T.dot(f)
        return tau_ext

    def _jacobian_mapping(
        self,
        stance: tuple[bool, ...],
        wrench: FloatArray,
        J_feet: FloatArray,
        v_feet: FloatArray,
        p_feet: FloatArray,
        R_feet: FloatArray,
        swing_pva: FloatArray,
        swing_yaw: FloatArray,
        J_hands: FloatArray,
        p_hands: FloatArray,
        v_hands: FloatArray,
        hand_des: FloatArray,
        hand_vel_des: FloatArray,
        tau_ext: FloatArray,
        q: FloatArray,
        v: FloatArray,
    ) -> FloatArray:
        """Baseline: stance legs tau = h - J' W; swing legs and arms tau = h + J' F_PD; the
        posture joints (`posture_joint_indices`) add M_jj times the posture acceleration
        (their own inertia, the coupling ignored, as a baseline may). Feet arrays are stacked
        per foot (J_feet (2, 6, nv), ...); swing_pva (n, 3, 3) and swing_yaw (n,) hold the
        targets of the n swinging feet in foot order; J_hands (2, 3, nv) are the hands'
        linear Jacobians; q (nq,), v (nv,) the state."""
        s = self.s
        h = self.robot.h - tau_ext
        tau_full = h.copy()
        i_sw = 0
        for k in range(2):
            cols = self._cols_leg[k]
            J = J_feet[k][:, cols]
            if stance[k]:
                tau_full[cols] -= J.T @ wrench[k]
            elif i_sw < len(swing_yaw):
                p_d, v_d, _ = swing_pva[i_sw]
                yaw_d = float(swing_yaw[i_sw])
                i_sw += 1
                F = s.swing_kp_force * (p_d - p_feet[k]) + s.swing_kd_force * (v_d - v_feet[k][:3])
                e = rotation_error(rot_z(yaw_d), R_feet[k])
                Mw = 20.0 * e - 1.0 * v_feet[k][3:]
                tau_full[cols] += J.T @ np.concatenate([F, Mw])
        for k in range(2):
            cols = self._cols_arm[k]
            F = s.hand_kp_force * (hand_des[k] - p_hands[k]) + s.hand_kd_force * (
                hand_vel_des[k] - v_hands[k]
            )
            tau_full[cols] += J_hands[k][:, cols].T @ F
        cols = self._cols_posture
        if len(cols):
            a_p = posture_acceleration(
                cols, self._q_posture, q, v, s.posture_kp_acc, s.posture_kd_acc
            )
            tau_full[cols] += np.diag(self.robot.M)[cols] * a_p
        return tau_full[6:]
