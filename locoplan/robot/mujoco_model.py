"""The robot's MuJoCo model: loading, the nominal keyframe, index maps by joint name.

The MJCF holds the robot alone. The simulator adds the floor, lights and objects through
`load_mujoco_spec(desc)` (a `mujoco.MjSpec`) and compiles it; every helper here works on
such an extended model too, because it looks joints up by name and checks what it finds.
Robot defaults in the MJCF live in class "hector" (not the main default class), so elements
added through the spec keep MuJoCo's built-in defaults.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

from locoplan.exceptions import RobotDescriptionError
from locoplan.robot.description import RobotDescription

IndexArray = NDArray[np.intp]


def load_mujoco_spec(desc: RobotDescription) -> mujoco.MjSpec:
    """Editable MJCF spec of the robot, for the simulator to attach a floor and objects."""
    try:
        return mujoco.MjSpec.from_file(str(desc.mjcf_path))
    except ValueError as exc:
        raise RobotDescriptionError(f"{desc.mjcf_path}: MuJoCo cannot parse it: {exc}") from exc


def load_mujoco_model(desc: RobotDescription) -> mujoco.MjModel:
    """Compiled MuJoCo model of the robot alone."""
    try:
        return mujoco.MjModel.from_xml_path(str(desc.mjcf_path))
    except ValueError as exc:
        raise RobotDescriptionError(f"{desc.mjcf_path}: MuJoCo cannot compile it: {exc}") from exc


def _joint_ids(desc: RobotDescription, model: mujoco.MjModel) -> list[int]:
    ids = []
    for name in desc.joint_names:
        jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
        if jid < 0 or model.jnt_type[jid] != mujoco.mjtJoint.mjJNT_HINGE:
            raise RobotDescriptionError(f"MuJoCo model has no hinge joint {name!r}")
        ids.append(int(jid))
    return ids


def _root_joint_id(desc: RobotDescription, model: mujoco.MjModel) -> int:
    bid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, desc.trunk_body)
    if bid < 0 or model.body_jntnum[bid] != 1:
        raise RobotDescriptionError(f"MuJoCo model has no free-jointed body {desc.trunk_body!r}")
    jid = int(model.body_jntadr[bid])
    if model.jnt_type[jid] != mujoco.mjtJoint.mjJNT_FREE:
        raise RobotDescriptionError(f"joint of {desc.trunk_body!r} is not a free joint")
    return jid


def joint_qpos_indices(desc: RobotDescription, model: mujoco.MjModel) -> IndexArray:
    """qpos indices (n_joints,) of the actuated joints, in `desc.joint_names` order."""
    return np.array(model.jnt_qposadr[_joint_ids(desc, model)], dtype=np.intp)


def joint_qvel_indices(desc: RobotDescription, model: mujoco.MjModel) -> IndexArray:
    """qvel indices (n_joints,) of the actuated joints, in `desc.joint_names` order."""
    return np.array(model.jnt_dofadr[_joint_ids(desc, model)], dtype=np.intp)


def root_qpos_indices(desc: RobotDescription, model: mujoco.MjModel) -> IndexArray:
    """qpos indices (7,) of the trunk free joint: position (3), quaternion w, x, y, z (4)."""
    start = int(model.jnt_qposadr[_root_joint_id(desc, model)])
    return np.arange(start, start + 7, dtype=np.intp)


def root_qvel_indices(desc: RobotDescription, model: mujoco.MjModel) -> IndexArray:
    """qvel indices (6,) of the trunk free joint: v_world (3), omega_base (3)."""
    start = int(model.jnt_dofadr[_root_joint_id(desc, model)])
    return np.arange(start, start + 6, dtype=np.intp)


def robot_qpos_indices(desc: RobotDescription, model: mujoco.MjModel) -> IndexArray:
    """qpos indices (7 + n_joints,) of the robot in pinocchio's coordinate order."""
    return np.concatenate([root_qpos_indices(desc, model), joint_qpos_indices(desc, model)])


def robot_qvel_indices(desc: RobotDescription, model: mujoco.MjModel) -> IndexArray:
    """qvel indices (6 + n_joints,) of the robot in pinocchio's coordinate order."""
    return np.concatenate([root_qvel_indices(desc, model), joint_qvel_indices(desc, model)])


def actuator_indices(desc: RobotDescription, model: mujoco.MjModel) -> IndexArray:
    """Actuator index (n_joints,) driving each joint of `desc.joint_names`, checked."""
    jids = _joint_ids(desc, model)
    by_joint = {
        int(model.actuator_trnid[a, 0]): a
        for a in range(model.nu)
        if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT
    }
    missing = [n for n, j in zip(desc.joint_names, jids, strict=True) if j not in by_joint]
    if missing:
        raise RobotDescriptionError(f"MuJoCo model has no actuator for joints {missing}")
    return np.array([by_joint[j] for j in jids], dtype=np.intp)


def nominal_qpos(desc: RobotDescription, model: mujoco.MjModel) -> NDArray[np.float64]:
    """Full qpos (model.nq,) of the nominal keyframe, checked against the description.

    Works on models extended through `load_mujoco_spec` (MuJoCo fills the added joints of
    the keyframe with their qpos0).
    """
    kid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, desc.nominal_keyframe)
    if kid < 0:
        raise RobotDescriptionError(f"MuJoCo model has no keyframe {desc.nominal_keyframe!r}")
    qpos = np.array(model.key_qpos[kid], dtype=np.float64)
    joints = qpos[joint_qpos_indices(desc, model)]
    z_base = qpos[root_qpos_indices(desc, model)[2]]
    # 1e-7 rad and 1e-9 m: robot.yaml states the pose to 1e-6 deg, the keyframe in radians.
    if not np.allclose(joints, desc.q_joints_nominal, atol=1e-7, rtol=0) or not np.isclose(
        z_base, desc.base_height_nominal, atol=1e-9, rtol=0
    ):
        raise RobotDescriptionError(
            f"keyframe {desc.nominal_keyframe!r} differs from the description's nominal pose"
        )
    return qpos
