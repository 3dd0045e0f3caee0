"""MuJoCo backend: reset / step / state, in the upkie style (the controller never sees mujoco).

The robot's free joint comes first in the scene (the robot spec is loaded before anything is
added), so robot qpos is [0:7 + n] and qvel [0:6 + n] for its n joints (HECTOR: [0:23] and
[0:22]); object free joints follow. States handed to
the controller are in pinocchio's convention (see `locoplan.robot.conventions`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt
from numba import njit

from locoplan.robot.conventions import mj_to_pin_state
from locoplan.robot.mujoco_model import joint_qpos_indices, joint_qvel_indices, nominal_qpos
from locoplan.sim.scene import Scene

FloatArray = npt.NDArray[np.float64]


# An explicit signature (any layout: MuJoCo's contact fields are strided views): compiled or
# loaded from the cache at import, never in the middle of a run.
@njit(
    "void(int32[:, :], float64[:, :], int32[:], int32[:], float64[:, :], float64[:],"
    " int32[:], int32[:], boolean, float64[:, :])",
    cache=True,
)
def _foot_forces(
    geom: npt.NDArray[np.int32],
    frame: FloatArray,
    efc_address: npt.NDArray[np.int32],
    dim: npt.NDArray[np.int32],
    friction: FloatArray,
    efc_force: FloatArray,
    geom_body: npt.NDArray[np.int32],
    feet: npt.NDArray[np.int32],
    pyramidal: bool,
    out: FloatArray,
) -> None:
    """Add to `out[k]` (3,) the world-frame force on foot body `feet[k]` of every contact.

    What `mj_contactForce` computes, for all contacts in one call: the force geom1 exerts on
    geom2 in the contact frame (normal, tangent 1, tangent 2) is the contact's block of
    `efc_force` (elliptic cones), or decoded from its pyramid edges (pyramidal: the normal is
    the sum of the edge forces, tangent i is (edge 2i - edge 2i+1) mu_i). The frame's rows are
    the normal (geom1 -> geom2) and the tangents, so f_world = frame^T f; a foot that is
    geom1 receives -f_world. Contacts excluded from the constraints (efc_address < 0) carry
    no force.
    """
    for i in range(geom.shape[0]):
        adr = efc_address[i]
        if adr < 0:
            continue
        b1 = geom_body[geom[i, 0]]
        b2 = geom_body[geom[i, 1]]
        for k in range(feet.size):
            fb = feet[k]
            if fb != b1 and fb != b2:
                continue
            n = dim[i]
            f0 = 0.0
            f1 = 0.0
            f2 = 0.0
            if n == 1:
                f0 = efc_force[adr]
            elif pyramidal:
                for j in range(2 * (n - 1)):
                    f0 += efc_force[adr + j]
                f1 = (efc_force[adr] - efc_force[adr + 1]) * friction[i, 0]
                f2 = (efc_force[adr + 2] - efc_force[adr + 3]) * friction[i, 1]
            else:
                f0 = efc_force[adr]
                f1 = efc_force[adr + 1]
                f2 = efc_force[adr + 2]
            sign = 1.0 if fb == b2 else -1.0
            for col in range(3):
                w = frame[i, col] * f0 + frame[i, 3 + col] * f1 + frame[i, 6 + col] * f2
                out[k, col] += sign * w


@dataclass(frozen=True, slots=True)
class RobotState:
    """Perfect state estimate at time `t` (s): q (7 + n,) and v (6 + n,) in pinocchio convention."""

    t: float
    q: FloatArray
    v: FloatArray


class MujocoBackend:
    """Owns MjData. `step(tau)` applies joint torques (N m, actuator order) for one physics step."""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.model = scene.model
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.dt = float(m.opt.timestep)
        self._foot_body_ids = [
            int(m.site_bodyid[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, name)])
            for name in scene.robot.foot_frames
        ]
        self.nq_robot = 7 + scene.robot.n_joints  # the free joint, then one hinge per joint
        self.nv_robot = 6 + scene.robot.n_joints
        self._trunk_body_id = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, scene.robot.trunk_body)
        self._geom_body = np.asarray(m.geom_bodyid)
        self._foot_bodies = np.array(self._foot_body_ids, dtype=np.int32)
        self._pyramidal = int(m.opt.cone) == int(mujoco.mjtCone.mjCONE_PYRAMIDAL)
        self.ctrl_low = np.asarray(m.actuator_ctrlrange[:, 0]).copy()
        self.ctrl_high = np.asarray(m.actuator_ctrlrange[:, 1]).copy()

    # -- lifecycle ---------------------------------------------------------------------------
    def reset(
        self,
        base_xy: tuple[float, float] = (0.0, 0.0),
        base_yaw: float = 0.0,
        hands_in_trunk: tuple[tuple[float, float, float], ...] | None = None,
    ) -> None:
        """Put the robot in its nominal standing pose at `base_xy`, yaw `base_yaw` (rad); with
        `hands_in_trunk` (one point per hand, m, trunk origin and yaw frame, in the robot
        description's hand order), the arms are posed so that the hand sites sit there (the
        plan starts the hands tucked when the scene is close to the robot)."""
        mujoco.mj_resetData(self.model, self.data)
        q0 = nominal_qpos(self.scene.robot, self.model)
        self.data.qpos[: self.nq_robot] = q0[: self.nq_robot]
        self.data.qpos[0] = base_xy[0]
        self.data.qpos[1] = base_xy[1]
        self.data.qpos[3:7] = [math.cos(base_yaw / 2), 0.0, 0.0, math.sin(base_yaw / 2)]
        mujoco.mj_forward(self.model, self.data)
        if hands_in_trunk is not None:
            self._pose_arms(hands_in_trunk, base_yaw)

    def _pose_arms(
        self, hands_in_trunk: tuple[tuple[float, float, float], ...], yaw: float
    ) -> None:
        """Damped Gauss-Newton on each arm's joints (3 or more) until its hand site is within
        0.1 mm of the target, within the joints' ranges. Converges in a few iterations from the
        nominal arm pose for targets inside the arm's reach; an unreachable target leaves the
        closest pose found."""
        m, d = self.model, self.data
        desc = self.scene.robot
        qadr = joint_qpos_indices(desc, m)
        vadr = joint_qvel_indices(desc, m)
        trunk = d.xpos[self._trunk_body_id].copy()
        c, s = math.cos(yaw), math.sin(yaw)
        jac = np.zeros((3, m.nv))
        for hand, target in enumerate(hands_in_trunk):
            site = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, desc.hand_frames[hand])
            joints = desc.arm_joint_indices[hand]
            goal = trunk + np.array(
                [c * target[0] - s * target[1], s * target[0] + c * target[1], target[2]]
            )
            for _ in range(50):
                err = goal - d.site_xpos[site]
                if float(np.linalg.norm(err)) < 1e-4:
                    break
                mujoco.mj_jacSite(m, d, jac, None, site)
                J = jac[:, vadr[joints]]
                dq = J.T @ np.linalg.solve(J @ J.T + 1e-4 * np.eye(3), err)
                for j, step in zip(joints, dq, strict=True):
                    jid = m.dof_jntid[vadr[j]]
                    lo, hi = m.jnt_range[jid]
                    d.qpos[qadr[j]] = min(max(d.qpos[qadr[j]] + step, lo), hi)
                mujoco.mj_forward(m, d)

    def step(self, tau: FloatArray) -> None:
        """Apply `tau` (n_joints,) through the torque actuators (the plant clips to
        ctrlrange)."""
        self.data.ctrl[:] = tau
        mujoco.mj_step(self.model, self.data)

    def step_held(self) -> None:
        """One physics step with the torques of the last `step` (MuJoCo keeps `ctrl`)."""
        mujoco.mj_step(self.model, self.data)

    # -- state -------------------------------------------------------------------------------
    @property
    def time(self) -> float:
        return float(self.data.time)

    def robot_state(self) -> RobotState:
        q, v = self.robot_qv()
        return RobotState(t=float(self.data.time), q=q, v=v)

    def robot_qv(self) -> tuple[FloatArray, FloatArray]:
        """`robot_state`'s q (7 + n,) and v (6 + n,) alone (the closed loop's per-tick call)."""
        d = self.data
        return mj_to_pin_state(d.qpos[: self.nq_robot], d.qvel[: self.nv_robot])

    def applied_torques(self) -> FloatArray:
        """Torques the actuators actually applied at the last step (after ctrlrange), N m."""
        return np.asarray(self.data.actuator_force).copy()

    def base_position(self) -> FloatArray:
        return np.asarray(self.data.qpos[0:3]).copy()

    def base_quat_wxyz(self) -> FloatArray:
        return np.asarray(self.data.qpos[3:7]).copy()

    def state_is_finite(self) -> bool:
        """True when qpos and qvel hold no NaN or inf."""
        return bool(np.all(np.isfinite(self.data.qpos)) and np.all(np.isfinite(self.data.qvel)))

    def foot_contact_forces(self) -> FloatArray:
        """Ground reaction force on each foot (2, 3), world frame, N (sum over contacts)."""
        out = np.zeros((2, 3))
        d = self.data
        if d.ncon == 0:
            return out
        c = d.contact
        _foot_forces(
            c.geom,
            c.frame,
            c.efc_address,
            c.dim,
            c.friction,
            d.efc_force,
            self._geom_body,
            self._foot_bodies,
            self._pyramidal,
            out,
        )
        return out

    def object_pose(self, body_id: int) -> tuple[FloatArray, FloatArray]:
        """Position (3,) and quaternion (w, x, y, z) of a body in the world."""
        return (
            np.asarray(self.data.xpos[body_id]).copy(),
            np.asarray(self.data.xquat[body_id]).copy(),
        )

    # -- disturbances ------------------------------------------------------------------------
    def set_trunk_force(self, force_world: FloatArray) -> None:
        """Apply a constant external force (N, world) at the trunk CoM until changed."""
        self.data.xfrc_applied[self._trunk_body_id, :3] = force_world
