"""Task-space acceleration tasks for the whole-body controller (Kim et al. 2019).

`build_tasks` stacks, in priority order: the stance contacts (J_c qdd + Jdot_c v = 0, five
rows per line foot: no constraint on roll about the foot's long axis, which the 5-DoF leg
cannot control), the trunk pose PD (position and orientation), then the swing feet
(position, pitch and yaw) and the hands. Pinocchio's conventions: Jacobians are
LOCAL_WORLD_ALIGNED (rows: linear then angular velocity in world axes). The arithmetic is
compiled (`locoplan.control.wbc_kernels.stack_tasks`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from locoplan.control.wbc import AccelerationTask
from locoplan.control.wbc_kernels import N_GAINS, stack_tasks

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class TaskGains:
    """Trunk PD gains on position and orientation (per axis, 1/s^2 and 1/s) and swing-foot
    gains (position 1/s^2, 1/s; orientation 1/s^2, 1/s)."""

    trunk_kp_pos: tuple[float, float, float]
    trunk_kd_pos: tuple[float, float, float]
    trunk_kp_rot: tuple[float, float, float]
    trunk_kd_rot: tuple[float, float, float]
    swing_kp: float
    swing_kd: float
    swing_kp_rot: float
    swing_kd_rot: float

    def packed(self) -> FloatArray:
        """The gains as `wbc_kernels.stack_tasks` takes them (N_GAINS,): trunk kp_pos,
        kd_pos, kp_rot, kd_rot (3 each), swing kp, kd, kp_rot, kd_rot."""
        out = np.array(
            [
                *self.trunk_kp_pos,
                *self.trunk_kd_pos,
                *self.trunk_kp_rot,
                *self.trunk_kd_rot,
                self.swing_kp,
                self.swing_kd,
                self.swing_kp_rot,
                self.swing_kd_rot,
            ],
            dtype=float,
        )
        assert out.shape == (N_GAINS,)
        return out


def rot_z(yaw: float) -> FloatArray:
    """Rotation matrix about z by `yaw` (rad)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation_error(R_des: FloatArray, R: FloatArray) -> FloatArray:
    """World-frame rotation vector e with exp([e]x) R = R_des (log map of R_des R')."""
    E = R_des.dot(R.T)
    (e00, e01, e02), (e10, e11, e12), (e20, e21, e22) = E.tolist()
    cos_t = max(-1.0, min(1.0, (e00 + e11 + e22 - 1.0) / 2.0))
    theta = math.acos(cos_t)
    f = 0.5 if theta < 1e-6 else theta / (2.0 * math.sin(theta))
    return np.array([f * (e21 - e12), f * (e02 - e20), f * (e10 - e01)])


def build_tasks(
    g: TaskGains,
    q: FloatArray,
    v: FloatArray,
    R_base: FloatArray,
    omega_world: FloatArray,
    p_base_des: FloatArray,
    v_base_des: FloatArray,
    yaw_des: float,
    yaw_rate_des: float,
    J_base: FloatArray,
    dJv_base: FloatArray,
    stance: tuple[bool, ...],
    J_feet: list[FloatArray],
    dJv_feet: list[FloatArray],
    v_feet: list[FloatArray],
    p_feet: FloatArray,
    R_feet: list[FloatArray],
    swing: list[tuple[FloatArray, FloatArray, FloatArray, float]],
    J_hands: list[FloatArray],
    dJv_hands: list[FloatArray],
    hand_acc: FloatArray,
    pitch_des: float = 0.0,
) -> list[AccelerationTask]:
    """Tasks in priority order. `swing` holds (p, v, a, yaw) targets of the swing feet in
    foot order; `hand_acc` (2, 3) the hands' commanded accelerations (world, m/s^2).

    The rows come from the compiled `wbc_kernels.stack_tasks` (the controller calls it
    directly with stacked arrays); this list form is for tests and tools."""
    swing_pva = np.zeros((2, 3, 3))
    swing_yaw = np.zeros(2)
    for j, (p_d, v_d, a_d, yaw_d) in enumerate(swing[:2]):
        swing_pva[j] = (p_d, v_d, a_d)
        swing_yaw[j] = yaw_d
    J, b, a, ends = stack_tasks(
        g.packed(),
        np.ascontiguousarray(q, dtype=float),
        np.ascontiguousarray(v, dtype=float),
        np.ascontiguousarray(R_base, dtype=float),
        np.ascontiguousarray(omega_world, dtype=float),
        np.ascontiguousarray(p_base_des, dtype=float),
        np.ascontiguousarray(v_base_des, dtype=float),
        float(yaw_des),
        float(pitch_des),
        float(yaw_rate_des),
        np.ascontiguousarray(J_base, dtype=float),
        np.ascontiguousarray(dJv_base, dtype=float),
        np.array(stance[:2], dtype=np.bool_),
        np.array(J_feet, dtype=float),
        np.array(dJv_feet, dtype=float),
        np.array(v_feet, dtype=float),
        np.ascontiguousarray(p_feet, dtype=float),
        np.array(R_feet, dtype=float),
        min(len(swing), 2),
        swing_pva,
        swing_yaw,
        np.array(J_hands, dtype=float).reshape(len(J_hands), 3, J_base.shape[1]),
        np.array(dJv_hands, dtype=float).reshape(len(J_hands), 3),
        np.ascontiguousarray(hand_acc, dtype=float).reshape(len(J_hands), 3),
    )
    tasks: list[AccelerationTask] = []
    start = 0
    for end in ends.tolist():
        tasks.append(AccelerationTask(J[start:end], b[start:end], a[start:end]))
        start = end
    return tasks
