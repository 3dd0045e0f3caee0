"""Robot description: `robots/<name>/robot.yaml` plus its MJCF file, checked against each other.

`load_robot_description("hector")` reads the YAML (limits, frame roles, nominal pose),
compiles the MJCF with MuJoCo once to read the total mass and to check that joint order,
joint ranges, actuator order and torque ranges, sites and the nominal keyframe agree with
the YAML. Everything downstream (MuJoCo plant, pinocchio model, controller) takes the
resulting `RobotDescription`; nothing else reads robot files.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray
from ruamel.yaml import YAML
from ruamel.yaml.error import YAMLError

import locoplan
from locoplan.exceptions import RobotDescriptionError

ROBOTS_DIR_ENV = "LOCOPLAN_ROBOTS_DIR"
SIDES = ("L", "R")
# Tolerances of the YAML <-> MJCF cross-check: the YAML states angles to 1e-6 deg.
_ANGLE_TOL = 1e-7  # rad
_LENGTH_TOL = 1e-9  # m, N m
# Defaults of the optional robot.yaml fields, HECTOR's figures (robots/hector/hector.xml: the
# `*_hand_sphere` and `*_foot_*` contact geoms; locoplan.plan.compile_plan's foothold spacing),
# so that a robot.yaml written before these fields existed describes HECTOR unchanged.
DEFAULT_HAND_RADIUS = 0.02  # m
DEFAULT_FOOT_SPHERE_RADIUS = 0.01  # m
DEFAULT_STANCE_WIDTH = 0.2  # m
# Defaults of robot.yaml's optional `planner` section: HECTOR's figures, those of
# `locoplan.plan.constants` (the plan's PlanGeometry defaults; tests/test_sim_robot_plan.py
# checks that the two agree), so that HECTOR's file needs no such section.
DEFAULT_HAND_DEFAULT = (0.28, 0.12, -0.05)  # m, left hand in trunk
DEFAULT_HAND_TUCK = (0.06, 0.15, -0.24)  # m, left hand in trunk
DEFAULT_CARRY_FORWARD = 0.30  # m
DEFAULT_THROW_STOP_OFFSET = 0.16  # m
DEFAULT_TRUNK_FRONT = 0.07  # m
DEFAULT_WALK_STRIDE = 0.18  # m
DEFAULT_HIP_YAW_RANGE_DEG = 30.0  # deg
DEFAULT_HAND_ACCEL_LIMIT = 9.0  # m/s^2 (constants.HAND_ACCEL_LIMIT)
DEFAULT_ARM_MOVING_MASS = 1.0  # kg (constants.ARM_MOVING_MASS)
DEFAULT_TUCK_LIFT_DURATION = 0.3  # s (constants.TUCK_LIFT_DURATION)
# The rigid body of the controller's MPC (robot.yaml `mpc_body`; `locoplan.control.controller.
# mpc_body_inertia`): "composite", the whole robot's locked-joint inertia at the nominal pose
# (HECTOR, the default), or "upper-body", the inertia of every body outside the legs about
# its own centre of mass, the legs' mass lumped at the CoM (H1: docs/robots.md compares them).
MPC_BODIES = ("composite", "upper-body")


def _empty_indices() -> NDArray[np.intp]:
    out = np.zeros(0, dtype=np.intp)
    out.flags.writeable = False
    return out


@dataclass(frozen=True, slots=True)
class RobotReach:
    """How far the arms reach (robot.yaml `reach`): the bodies whose origins are the shoulder
    centres, ("L", "R"); the longest shoulder-centre-to-hand-site distance `max` (m) and that
    distance in the nominal pose, `nominal` (m)."""

    shoulder_bodies: tuple[str, str]
    max: float
    nominal: float


@dataclass(frozen=True, slots=True)
class PlannerFigures:
    """robot.yaml's optional `planner` section: what the plan compiler needs of the robot
    beyond its limits and frames (m, rad; poses of the LEFT hand relative to the trunk origin
    in its yaw-only frame, the right hand mirrors y). Absent keys take HECTOR's figures
    (DEFAULT_*). `hand_default`: where the hands rest and start (the keyframe's hand
    positions, so that the arms start at rest); `hand_tuck`: close to the body and below
    the tables; `carry_forward`: a held object's centre ahead of the trunk origin;
    `throw_stop_offset`: a throw's follow-through beyond the carry pose; `trunk_front`: the
    trunk's front face ahead of its origin; `walk_stride`: how far a stance foot may move
    ahead of or behind its hip in one gait period; `hip_yaw_range`: the hip yaw joint's
    range either side of straight ahead. `hand_accel_limit` (m/s^2): the peak acceleration of
    the hands' free moves (opening, retreat, tuck, slide), `arm_moving_mass` (kg): the arms'
    share of the mass those moves accelerate (with a held object's, it sets a pull-in's
    acceleration), `tuck_lift_duration` (s): the rise from the tucked pose to a reach's
    height (constants' HAND_ACCEL_LIMIT, ARM_MOVING_MASS and TUCK_LIFT_DURATION say how each
    scales from HECTOR's)."""

    hand_default: tuple[float, float, float] = DEFAULT_HAND_DEFAULT
    hand_tuck: tuple[float, float, float] = DEFAULT_HAND_TUCK
    carry_forward: float = DEFAULT_CARRY_FORWARD
    throw_stop_offset: float = DEFAULT_THROW_STOP_OFFSET
    trunk_front: float = DEFAULT_TRUNK_FRONT
    walk_stride: float = DEFAULT_WALK_STRIDE
    hip_yaw_range: float = math.radians(DEFAULT_HIP_YAW_RANGE_DEG)
    hand_accel_limit: float = DEFAULT_HAND_ACCEL_LIMIT
    arm_moving_mass: float = DEFAULT_ARM_MOVING_MASS
    tuck_lift_duration: float = DEFAULT_TUCK_LIFT_DURATION


@dataclass(frozen=True, slots=True, eq=False)
class RobotDescription:
    """A robot's limits, frames and nominal pose, in SI units and radians.

    Joint arrays have shape (n_joints,) and follow `joint_names`, which is the MJCF tree
    order, the actuator order and pinocchio's joint order after the free flyer. Side-indexed
    tuples are in ("L", "R") order. Arrays are read-only. The legs, the arms (any number of
    joints each) and the torso (joints in no limb, possibly none) partition the joints.

    The fields after `arm_joint_indices` are optional in robot.yaml; their defaults are
    HECTOR's (DEFAULT_*), and `reach` is None when the file gives none.
    """

    name: str
    mjcf_path: Path
    joint_names: tuple[str, ...]
    torque_limits: NDArray[np.float64]  # N m, symmetric: |tau_i| <= torque_limits[i]
    velocity_limits: NDArray[np.float64]  # rad/s, symmetric
    q_lower: NDArray[np.float64]  # rad
    q_upper: NDArray[np.float64]  # rad
    trunk_body: str
    imu_site: str
    foot_frames: tuple[str, str]  # sole sites, ("L", "R")
    hand_frames: tuple[str, str]  # hand contact sites, ("L", "R")
    foot_toe: float  # m ahead of the sole site along the foot's x axis
    foot_heel: float  # m behind the sole site
    nominal_keyframe: str
    q_joints_nominal: NDArray[np.float64]  # rad
    base_height_nominal: float  # trunk origin above the soles in the nominal pose, m
    fall_height: float  # trunk origin below this height means fallen, m
    total_mass: float  # kg, from the MJCF
    leg_joint_indices: tuple[NDArray[np.intp], NDArray[np.intp]]  # into joint_names, ("L","R")
    arm_joint_indices: tuple[NDArray[np.intp], NDArray[np.intp]]
    torso_joint_indices: NDArray[np.intp] = field(default_factory=_empty_indices)
    hand_radius: float = DEFAULT_HAND_RADIUS  # m, the hand contact sphere's radius
    foot_sphere_radius: float = DEFAULT_FOOT_SPHERE_RADIUS  # m, the sole spheres' radius
    stance_width: float = DEFAULT_STANCE_WIDTH  # m, lateral distance of the planned footholds
    reach: RobotReach | None = None
    planner: PlannerFigures = PlannerFigures()
    mpc_body: str = MPC_BODIES[0]  # one of MPC_BODIES
    # The hands' Cartesian kp (1/s^2) on the way to a grasp, with the target's acceleration
    # fed forward (robot.yaml `hand_approach_kp`; `LocoManipulationController._hand_gains`);
    # None (HECTOR): the controller's hand gains throughout.
    hand_approach_kp: float | None = None

    @property
    def n_joints(self) -> int:
        """Number of actuated joints."""
        return len(self.joint_names)

    @property
    def base_frame(self) -> str:
        """Frame of the floating base: the trunk body (MuJoCo body, pinocchio BODY frame)."""
        return self.trunk_body


def robots_dir() -> Path:
    """The directory holding `<name>/robot.yaml`, the first of: $LOCOPLAN_ROBOTS_DIR; the
    robots an installed package carries (`locoplan/_data/robots`, see setup.py); the
    repository checkout's `robots/` (beside the `locoplan/` package)."""
    override = os.environ.get(ROBOTS_DIR_ENV)
    if override:
        return Path(override).expanduser()
    package = Path(locoplan.__file__).resolve().parent
    installed = package / "_data" / "robots"
    checkout = package.parent / "robots"
    if not installed.is_dir() and checkout.is_dir():
        return checkout
    return installed


def resolve_robot_yaml(name_or_path: str | Path) -> Path:
    """Path of the robot.yaml for a robot name, a robot directory or a robot.yaml path. A
    name of a robot under `robots_dir()` means that robot even where a directory of that
    name happens to be in the working directory (a folder of H1 scripts named `h1/` made
    `robot: h1` look for `h1/robot.yaml` there); a directory counts only with a robot.yaml."""
    candidate = Path(name_or_path)
    named = robots_dir() / str(name_or_path) / "robot.yaml"
    if candidate.suffix in (".yaml", ".yml"):
        path = candidate
    elif named.is_file() or not (candidate / "robot.yaml").is_file():
        path = named
    else:
        path = candidate / "robot.yaml"
    if not path.is_file():
        raise RobotDescriptionError(
            f"robot {name_or_path!r}: no robot description at {path} "
            f"(robots directory: {robots_dir()}, override with ${ROBOTS_DIR_ENV})"
        )
    return path


def load_robot_description(name_or_path: str | Path = "hector") -> RobotDescription:
    """Load and cross-check a robot description.

    `name_or_path` is a robot name (looked up as `<robots_dir()>/<name>/robot.yaml`), a
    robot directory or the path of a robot.yaml. Raises `RobotDescriptionError` with the
    file and the offending entry when anything is missing or inconsistent.
    """
    path = resolve_robot_yaml(name_or_path)
    try:
        raw = YAML(typ="safe").load(path.read_text())
    except (OSError, YAMLError) as exc:
        raise RobotDescriptionError(f"{path}: cannot read YAML: {exc}") from exc
    reader = _Reader(path, raw)

    joints = reader.get_list("joints")
    names: list[str] = []
    torque, velocity, lower, upper = [], [], [], []
    for i, entry in enumerate(joints):
        row = _Reader(path, entry, f"joints[{i}]")
        names.append(row.get_str("name"))
        torque.append(row.get_positive("torque_Nm"))
        velocity.append(row.get_positive("velocity_rad_s"))
        lo, hi = row.get_pair("range_deg")
        if not lo < hi:
            raise reader.error(f"joints[{i}].range_deg: lower {lo} must be below upper {hi}")
        lower.append(np.radians(lo))
        upper.append(np.radians(hi))
    if len(set(names)) != len(names):
        raise reader.error(f"joints: duplicate joint names in {names}")
    joint_names = tuple(names)

    legs = tuple(_indices(reader, "legs", side, joint_names) for side in SIDES)
    arms = tuple(_indices(reader, "arms", side, joint_names) for side in SIDES)
    torso = _empty_indices()
    if "torso" in reader.node:
        torso = _indices_of(reader, "torso", reader.get_list("torso"), joint_names)
    _check_partition(reader, joint_names, [*legs, *arms, torso])

    contacts = reader.get_sub("contacts")
    feet, hands = contacts.get_sub("feet"), contacts.get_sub("hands")
    foot = reader.get_sub("foot")
    reach = _reach(reader.get_sub("reach")) if "reach" in reader.node else None
    planner = _planner(reader.get_sub("planner")) if "planner" in reader.node else None
    nominal = reader.get_sub("nominal")
    nominal_deg = nominal.get_sub("joints_deg")
    if set(nominal_deg.keys()) != set(joint_names):
        raise nominal_deg.error(
            f"must give exactly the joints {list(joint_names)}, got {list(nominal_deg.keys())}"
        )
    q_nominal = np.radians([nominal_deg.get_float(n) for n in joint_names])

    mjcf_path = (path.parent / reader.get_str("mjcf")).resolve()
    desc = RobotDescription(
        name=reader.get_str("name"),
        mjcf_path=mjcf_path,
        joint_names=joint_names,
        torque_limits=_frozen(torque),
        velocity_limits=_frozen(velocity),
        q_lower=_frozen(lower),
        q_upper=_frozen(upper),
        trunk_body=reader.get_str("trunk_body"),
        imu_site=reader.get_str("imu_site"),
        foot_frames=(feet.get_str("L"), feet.get_str("R")),
        hand_frames=(hands.get_str("L"), hands.get_str("R")),
        foot_toe=foot.get_positive("toe"),
        foot_heel=foot.get_positive("heel"),
        nominal_keyframe=reader.get_str("nominal_keyframe"),
        q_joints_nominal=_frozen(q_nominal),
        base_height_nominal=nominal.get_positive("trunk_height"),
        fall_height=reader.get_positive("fall_height"),
        total_mass=0.0,
        leg_joint_indices=(legs[0], legs[1]),
        arm_joint_indices=(arms[0], arms[1]),
        torso_joint_indices=torso,
        hand_radius=contacts.get_positive_or("hand_radius", DEFAULT_HAND_RADIUS),
        foot_sphere_radius=contacts.get_positive_or(
            "foot_sphere_radius", DEFAULT_FOOT_SPHERE_RADIUS
        ),
        stance_width=reader.get_positive_or("stance_width", DEFAULT_STANCE_WIDTH),
        reach=reach,
        planner=planner if planner is not None else PlannerFigures(),
        mpc_body=reader.get_choice_or("mpc_body", MPC_BODIES),
        hand_approach_kp=(
            reader.get_positive("hand_approach_kp") if "hand_approach_kp" in reader.node else None
        ),
    )
    if np.any(desc.q_joints_nominal < desc.q_lower) or np.any(desc.q_joints_nominal > desc.q_upper):
        raise nominal_deg.error("nominal joint angles must lie within the joint ranges")
    if not desc.fall_height < desc.base_height_nominal:
        raise reader.error("fall_height must be below nominal.trunk_height")
    return replace(desc, total_mass=_check_mjcf(desc, path))


def _check_mjcf(desc: RobotDescription, yaml_path: Path) -> float:
    """Compile the MJCF, check it against the YAML, return the total mass (kg)."""
    where = f"{yaml_path} vs {desc.mjcf_path}"
    if not desc.mjcf_path.is_file():
        raise RobotDescriptionError(f"{yaml_path}: MJCF file {desc.mjcf_path} not found")
    try:
        model = mujoco.MjModel.from_xml_path(str(desc.mjcf_path))
    except ValueError as exc:
        raise RobotDescriptionError(f"{desc.mjcf_path}: MuJoCo cannot compile it: {exc}") from exc

    n = desc.n_joints
    if not _has(model, mujoco.mjtObj.mjOBJ_BODY, desc.trunk_body):
        raise RobotDescriptionError(f"{where}: trunk body {desc.trunk_body!r} missing")
    trunk = model.body(desc.trunk_body).id
    root_jnt = int(model.body_jntadr[trunk])
    if (
        model.body_jntnum[trunk] != 1
        or model.jnt_type[root_jnt] != mujoco.mjtJoint.mjJNT_FREE
        or model.nq != 7 + n
    ):
        raise RobotDescriptionError(
            f"{where}: expected one free joint on {desc.trunk_body!r} and {n} hinges "
            f"(nq {7 + n}), got nq {model.nq}"
        )
    mj_names = tuple(model.joint(j).name for j in range(model.njnt) if j != root_jnt)
    if mj_names != desc.joint_names:
        raise RobotDescriptionError(f"{where}: joint order differs: MJCF {list(mj_names)}")
    hinge_ids = [model.joint(name).id for name in desc.joint_names]
    if np.any(model.jnt_type[hinge_ids] != mujoco.mjtJoint.mjJNT_HINGE):
        raise RobotDescriptionError(f"{where}: every actuated joint must be a hinge")
    ranges = model.jnt_range[hinge_ids]
    if not (
        model.jnt_limited[hinge_ids].all()
        and np.allclose(ranges[:, 0], desc.q_lower, atol=_ANGLE_TOL, rtol=0)
        and np.allclose(ranges[:, 1], desc.q_upper, atol=_ANGLE_TOL, rtol=0)
    ):
        raise RobotDescriptionError(
            f"{where}: joint ranges differ: MJCF {np.degrees(ranges).round(3).tolist()} deg"
        )

    if model.nu != n or [int(model.actuator_trnid[a, 0]) for a in range(n)] != hinge_ids:
        raise RobotDescriptionError(f"{where}: need one actuator per joint, in joint order")
    ctrl = model.actuator_ctrlrange
    if not (
        model.actuator_ctrllimited.all()
        and np.allclose(model.actuator_gear[:, 0], 1.0)
        and np.allclose(ctrl[:, 1], desc.torque_limits, atol=_LENGTH_TOL, rtol=0)
        and np.allclose(ctrl[:, 0], -desc.torque_limits, atol=_LENGTH_TOL, rtol=0)
    ):
        raise RobotDescriptionError(f"{where}: actuator ctrlrange must be +-torque_Nm, gear 1")

    for site in (desc.imu_site, *desc.foot_frames, *desc.hand_frames):
        if not _has(model, mujoco.mjtObj.mjOBJ_SITE, site):
            raise RobotDescriptionError(f"{where}: site {site!r} missing")
    for body in desc.reach.shoulder_bodies if desc.reach is not None else ():
        if not _has(model, mujoco.mjtObj.mjOBJ_BODY, body):
            raise RobotDescriptionError(f"{where}: reach shoulder body {body!r} missing")

    if not _has(model, mujoco.mjtObj.mjOBJ_KEY, desc.nominal_keyframe):
        raise RobotDescriptionError(f"{where}: keyframe {desc.nominal_keyframe!r} missing")
    key_qpos = model.key(desc.nominal_keyframe).qpos
    qadr = model.jnt_qposadr[hinge_ids]
    if not (
        np.allclose(key_qpos[qadr], desc.q_joints_nominal, atol=_ANGLE_TOL, rtol=0)
        and abs(key_qpos[model.jnt_qposadr[root_jnt] + 2] - desc.base_height_nominal) < _LENGTH_TOL
    ):
        raise RobotDescriptionError(
            f"{where}: keyframe {desc.nominal_keyframe!r} differs from nominal: "
            f"{np.degrees(key_qpos[qadr]).round(6).tolist()} deg"
        )
    return float(np.sum(model.body_mass))


def _has(model: mujoco.MjModel, kind: mujoco.mjtObj, name: str) -> bool:
    return bool(mujoco.mj_name2id(model, kind, name) >= 0)


def _frozen(values: Any) -> NDArray[np.float64]:
    array = np.array(values, dtype=np.float64)
    array.flags.writeable = False
    return array


def _indices(
    reader: _Reader, key: str, side: str, joint_names: tuple[str, ...]
) -> NDArray[np.intp]:
    return _indices_of(reader, f"{key}.{side}", reader.get_sub(key).get_list(side), joint_names)


def _indices_of(
    reader: _Reader, where: str, names: list[Any], joint_names: tuple[str, ...]
) -> NDArray[np.intp]:
    unknown = [n for n in names if n not in joint_names]
    if unknown:
        raise reader.error(f"{where}: unknown joints {unknown}")
    idx = np.array([joint_names.index(n) for n in names], dtype=np.intp)
    idx.flags.writeable = False
    return idx


def _check_partition(
    reader: _Reader, joint_names: tuple[str, ...], groups: list[NDArray[np.intp]]
) -> None:
    """Legs, arms and torso must list every joint exactly once; the error names the joints
    listed nowhere and those listed twice."""
    counts = np.bincount(np.concatenate(groups), minlength=len(joint_names))
    missing = [joint_names[i] for i in np.flatnonzero(counts == 0)]
    repeated = [joint_names[i] for i in np.flatnonzero(counts > 1)]
    if missing or repeated:
        parts = [f"not listed: {missing}"] if missing else []
        parts += [f"listed more than once: {repeated}"] if repeated else []
        raise reader.error(
            "legs, arms and torso must list every joint exactly once (" + "; ".join(parts) + ")"
        )


def _reach(node: _Reader) -> RobotReach:
    shoulders = node.get_sub("shoulders")
    reach = RobotReach(
        shoulder_bodies=(shoulders.get_str("L"), shoulders.get_str("R")),
        max=node.get_positive("max"),
        nominal=node.get_positive("nominal"),
    )
    if not reach.nominal <= reach.max:
        raise node.error(f"nominal {reach.nominal} must not exceed max {reach.max}")
    return reach


def _planner(node: _Reader) -> PlannerFigures:
    def point(key: str, default: tuple[float, float, float]) -> tuple[float, float, float]:
        if key not in node.node:
            return default
        value = node.node[key]
        ok = isinstance(value, list) and len(value) == 3
        if not ok or not all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
            for v in value
        ):
            raise node.error(
                f"{key!r} must be a list of three numbers [x, y, z] (m), got {value!r}"
            )
        if value[1] <= 0.0:
            raise node.error(f"{key!r}: the left hand's y must be positive, got {value[1]!r}")
        return (float(value[0]), float(value[1]), float(value[2]))

    throw_stop = DEFAULT_THROW_STOP_OFFSET
    if "throw_stop_offset" in node.node:
        throw_stop = node.get_float("throw_stop_offset")
        if throw_stop < 0.0:
            raise node.error(f"'throw_stop_offset' must not be negative, got {throw_stop!r}")
    hip_yaw = math.radians(DEFAULT_HIP_YAW_RANGE_DEG)
    if "hip_yaw_range_deg" in node.node:
        hip_yaw = math.radians(node.get_positive("hip_yaw_range_deg"))
    return PlannerFigures(
        hand_default=point("hand_default", DEFAULT_HAND_DEFAULT),
        hand_tuck=point("hand_tuck", DEFAULT_HAND_TUCK),
        carry_forward=node.get_positive_or("carry_forward", DEFAULT_CARRY_FORWARD),
        throw_stop_offset=throw_stop,
        trunk_front=node.get_positive_or("trunk_front", DEFAULT_TRUNK_FRONT),
        walk_stride=node.get_positive_or("walk_stride", DEFAULT_WALK_STRIDE),
        hip_yaw_range=hip_yaw,
        hand_accel_limit=node.get_positive_or("hand_accel_limit", DEFAULT_HAND_ACCEL_LIMIT),
        arm_moving_mass=node.get_positive_or("arm_moving_mass", DEFAULT_ARM_MOVING_MASS),
        tuck_lift_duration=node.get_positive_or("tuck_lift_duration", DEFAULT_TUCK_LIFT_DURATION),
    )


class _Reader:
    """Typed access to one YAML mapping, raising `RobotDescriptionError` with the key path."""

    def __init__(self, path: Path, node: Any, where: str = "") -> None:
        self.path, self.where = path, where
        if not isinstance(node, dict):
            raise self.error(f"expected a mapping, got {type(node).__name__}")
        self.node: dict[str, Any] = node

    def error(self, message: str) -> RobotDescriptionError:
        prefix = f"{self.where}: " if self.where else ""
        return RobotDescriptionError(f"{self.path}: {prefix}{message}")

    def keys(self) -> list[str]:
        return [str(k) for k in self.node]

    def _get(self, key: str) -> Any:
        if key not in self.node:
            raise self.error(f"missing key {key!r}")
        return self.node[key]

    def _key(self, key: str) -> str:
        return f"{self.where}.{key}" if self.where else key

    def get_sub(self, key: str) -> _Reader:
        return _Reader(self.path, self._get(key), self._key(key))

    def get_list(self, key: str) -> list[Any]:
        value = self._get(key)
        if not isinstance(value, list) or not value:
            raise self.error(f"{key!r} must be a non-empty list")
        return value

    def get_str(self, key: str) -> str:
        value = self._get(key)
        if not isinstance(value, str) or not value:
            raise self.error(f"{key!r} must be a non-empty string, got {value!r}")
        return value

    def get_float(self, key: str) -> float:
        value = self._get(key)
        if isinstance(value, bool) or not isinstance(value, int | float) or not np.isfinite(value):
            raise self.error(f"{key!r} must be a finite number, got {value!r}")
        return float(value)

    def get_positive(self, key: str) -> float:
        value = self.get_float(key)
        if value <= 0.0:
            raise self.error(f"{key!r} must be positive, got {value!r}")
        return value

    def get_positive_or(self, key: str, default: float) -> float:
        """`get_positive` for an optional key: `default` when absent."""
        return self.get_positive(key) if key in self.node else default

    def get_choice_or(self, key: str, choices: tuple[str, ...]) -> str:
        """An optional string among `choices`: the first of them when absent."""
        if key not in self.node:
            return choices[0]
        value = self.get_str(key)
        if value not in choices:
            raise self.error(f"{key!r} must be one of {list(choices)}, got {value!r}")
        return value

    def get_pair(self, key: str) -> tuple[float, float]:
        value = self._get(key)
        ok = isinstance(value, list) and len(value) == 2
        if not ok or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value):
            raise self.error(f"{key!r} must be a list of two numbers, got {value!r}")
        return float(value[0]), float(value[1])
