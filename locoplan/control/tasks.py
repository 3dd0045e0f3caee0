"""Task-space acceleration tasks for the whole-body controller (Kim et al. 2019).

`build_tasks` stacks, in priority order: the stance contacts (J_c qdd + Jdot_c v = 0, five
rows per line foot: no constraint on roll about the foot's long axis, which the 5-DoF leg
cannot control), the trunk pose PD (position and orientation), then the swing feet
(position, pitch and yaw) and the hands. Pure numpy, pinocchio's conventions: Jacobians are
LOCAL_WORLD_ALIGNED (rows: linear then angular velocity in world axes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from locoplan.control.wbc import AccelerationTask

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


def rot_z(yaw: float) -> FloatArray:
    """Rotation matrix about z by `yaw` (rad)."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def rotation_error(R_des: FloatArray, R: FloatArray) -> FloatArray:
    """World-frame rotation vector e with exp([e]x) R = R_des (log map of R_des R')."""
    E = R_des @ R.T
    cos_t = max(-1.0, min(1.0, (float(np.trace(E)) - 1.0) / 2.0))
    theta = math.acos(cos_t)
    w = np.array([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]])
    if theta < 1e-6:
        return 0.5 * w
    return theta / (2.0 * math.sin(theta)) * w


def _line_foot_rows(
    J: FloatArray, dJv: FloatArray, R_foot: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The 5 controllable rows of a line foot's Jacobian and drift: linear (3) and angular
    about the foot's own y and z axes (2)."""
    Jang = R_foot.T @ J[3:]
    aang = R_foot.T @ dJv[3:]
    return np.vstack([J[:3], Jang[1:]]), np.concatenate([dJv[:3], aang[1:]])


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
) -> list[AccelerationTask]:
    """Tasks in priority order. `swing` holds (p, v, a, yaw) targets of the swing feet in
    foot order; `hand_acc` (2, 3) the hands' commanded accelerations (world, m/s^2)."""
    tasks: list[AccelerationTask] = []
    rows_J, rows_b = [], []
    for k in range(2):
        if stance[k]:
            Jk, bk = _line_foot_rows(J_feet[k], dJv_feet[k], R_feet[k])
            rows_J.append(Jk)
            rows_b.append(bk)
    if rows_J:
        Jc = np.vstack(rows_J)
        tasks.append(AccelerationTask(Jc, np.concatenate(rows_b), np.zeros(Jc.shape[0])))
    e_rot = rotation_error(rot_z(yaw_des), R_base)
    w_des = np.array([0.0, 0.0, yaw_rate_des])
    acc_rot = np.asarray(g.trunk_kp_rot) * e_rot + np.asarray(g.trunk_kd_rot) * (
        w_des - omega_world
    )
    acc_pos = np.asarray(g.trunk_kp_pos) * (p_base_des - q[:3]) + np.asarray(g.trunk_kd_pos) * (
        v_base_des - R_base @ v[:3]
    )
    # Position and orientation in one level: the base's 6 DoF are independent, so stacking
    # them costs one 6x6 solve instead of two 3x3 ones and changes nothing.
    tasks.append(AccelerationTask(J_base, dJv_base, np.concatenate([acc_pos, acc_rot])))
    rows_J, rows_b, rows_a = [], [], []
    i_sw = 0
    for k in range(2):
        if stance[k] or i_sw >= len(swing):
            continue
        p_d, v_d, a_d, yaw_d = swing[i_sw]
        i_sw += 1
        a_lin = a_d + g.swing_kp * (p_d - p_feet[k]) + g.swing_kd * (v_d - v_feet[k][:3])
        Rf = R_feet[k]
        e = Rf.T @ rotation_error(rot_z(yaw_d), Rf)
        a_ang = g.swing_kp_rot * e - g.swing_kd_rot * (Rf.T @ v_feet[k][3:])
        Jk, bk = _line_foot_rows(J_feet[k], dJv_feet[k], Rf)
        rows_J.append(Jk)
        rows_b.append(bk)
        rows_a.append(np.concatenate([a_lin, a_ang[1:]]))
    for k in range(2):
        rows_J.append(J_hands[k])
        rows_b.append(dJv_hands[k])
        rows_a.append(hand_acc[k])
    tasks.append(
        AccelerationTask(np.vstack(rows_J), np.concatenate(rows_b), np.concatenate(rows_a))
    )
    return tasks
