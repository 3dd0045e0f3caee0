"""MuJoCo backend: reset / step / state, in the upkie style (the controller never sees mujoco).

The robot's free joint comes first in the scene (the robot spec is loaded before anything is
added), so robot qpos is [0:23] and qvel [0:22]; object free joints follow. States handed to
the controller are in pinocchio's convention (see `locoplan.robot.conventions`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt

from locoplan.robot.conventions import mj_to_pin_q, mj_to_pin_v
from locoplan.robot.mujoco_model import nominal_qpos
from locoplan.sim.scene import Scene

FloatArray = npt.NDArray[np.float64]

NQ_ROBOT = 23
NV_ROBOT = 22


@dataclass(frozen=True, slots=True)
class RobotState:
    """Perfect state estimate at time `t` (s): q (23,) and v (22,) in pinocchio convention."""

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
        self._trunk_body_id = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "trunk")
        self._geom_body = np.asarray(m.geom_bodyid)
        self._wrench = np.zeros(6)
        self.ctrl_low = np.asarray(m.actuator_ctrlrange[:, 0]).copy()
        self.ctrl_high = np.asarray(m.actuator_ctrlrange[:, 1]).copy()

    # -- lifecycle ---------------------------------------------------------------------------
    def reset(self, base_xy: tuple[float, float] = (0.0, 0.0), base_yaw: float = 0.0) -> None:
        """Put the robot in its nominal standing pose at `base_xy`, yaw `base_yaw` (rad)."""
        mujoco.mj_resetData(self.model, self.data)
        q0 = nominal_qpos(self.scene.robot, self.model)
        self.data.qpos[:NQ_ROBOT] = q0[:NQ_ROBOT]
        self.data.qpos[0] = base_xy[0]
        self.data.qpos[1] = base_xy[1]
        self.data.qpos[3:7] = [math.cos(base_yaw / 2), 0.0, 0.0, math.sin(base_yaw / 2)]
        mujoco.mj_forward(self.model, self.data)

    def step(self, tau: FloatArray) -> None:
        """Apply `tau` (16,) through the torque actuators (the plant clips to ctrlrange)."""
        self.data.ctrl[:] = tau
        mujoco.mj_step(self.model, self.data)

    # -- state -------------------------------------------------------------------------------
    @property
    def time(self) -> float:
        return float(self.data.time)

    def robot_state(self) -> RobotState:
        qpos = self.data.qpos[:NQ_ROBOT]
        qvel = self.data.qvel[:NV_ROBOT]
        return RobotState(t=self.time, q=mj_to_pin_q(qpos), v=mj_to_pin_v(qpos, qvel))

    def applied_torques(self) -> FloatArray:
        """Torques the actuators actually applied at the last step (after ctrlrange), N m."""
        return np.asarray(self.data.actuator_force).copy()

    def base_position(self) -> FloatArray:
        return np.asarray(self.data.qpos[0:3]).copy()

    def base_quat_wxyz(self) -> FloatArray:
        return np.asarray(self.data.qpos[3:7]).copy()

    def state_is_finite(self) -> bool:
        return bool(np.all(np.isfinite(self.data.qpos)) and np.all(np.isfinite(self.data.qvel)))

    def foot_contact_forces(self) -> FloatArray:
        """Ground reaction force on each foot (2, 3), world frame, N (sum over contacts)."""
        out = np.zeros((2, 3))
        d, m = self.data, self.model
        for i in range(d.ncon):
            c = d.contact[i]
            b1 = self._geom_body[c.geom1]
            b2 = self._geom_body[c.geom2]
            for k, fb in enumerate(self._foot_body_ids):
                if fb not in (b1, b2):
                    continue
                mujoco.mj_contactForce(m, d, i, self._wrench)
                # The contact frame's first row is the normal, pointing from geom1 to geom2;
                # mj_contactForce gives the force that geom1 exerts on geom2 in that frame.
                f_world = c.frame.reshape(3, 3).T @ self._wrench[:3]
                out[k] += f_world if fb == b2 else -f_world
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
