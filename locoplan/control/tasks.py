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
    E = R_des.dot(R.T)
    (e00, e01, e02), (e10, e11, e12), (e20, e21, e22) = E.tolist()
    cos_t = max(-1.0, min(1.0, (e00 + e11 + e22 - 1.0) / 2.0))
    theta = math.acos(cos_t)
    f = 0.5 if theta < 1e-6 else theta / (2.0 * math.sin(theta))
    return np.array([f * (e21 - e12), f * (e02 - e20), f * (e10 - e01)])


Rows = list[list[float]]


def _yaw_error(yaw: float, R: Rows) -> tuple[float, float, float]:
    """`rotation_error(rot_z(yaw), R)` on plain floats (R as row lists): the log map of
    E = R_z(yaw) R'."""
    c, s = math.cos(yaw), math.sin(yaw)
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R
    e00, e01 = c * r00 - s * r01, c * r10 - s * r11
    e10, e11 = s * r00 + c * r01, s * r10 + c * r11
    e02, e12 = c * r20 - s * r21, s * r20 + c * r21
    cos_t = max(-1.0, min(1.0, (e00 + e11 + r22 - 1.0) / 2.0))
    theta = math.acos(cos_t)
    f = 0.5 if theta < 1e-6 else theta / (2.0 * math.sin(theta))
    return f * (r12 - e12), f * (e02 - r02), f * (e10 - e01)


def _line_foot_rows(
    J: FloatArray, dJv: FloatArray, R_foot: FloatArray, J_out: FloatArray, b_out: FloatArray
) -> None:
    """Write the 5 controllable rows of a line foot's Jacobian and drift into J_out (5, nv)
    and b_out (5,): linear (3) and angular about the foot's own y and z axes (2)."""
    Ryz = R_foot[:, 1:].T
    J_out[:3] = J[:3]
    Ryz.dot(J[3:], out=J_out[3:])
    b_out[:3] = dJv[:3]
    b_out[3:] = Ryz.dot(dJv[3:])


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
    nv = J_base.shape[1]
    tasks: list[AccelerationTask] = []
    feet = [k for k in range(2) if stance[k]]
    if feet:
        n = 5 * len(feet)
        Jc = np.empty((n, nv))
        bc = np.empty(n)
        for i, k in enumerate(feet):
            rows = slice(5 * i, 5 * i + 5)
            _line_foot_rows(J_feet[k], dJv_feet[k], R_feet[k], Jc[rows], bc[rows])
        tasks.append(AccelerationTask(Jc, bc, np.zeros(n)))
    # Position and orientation in one level: the base's 6 DoF are independent, so stacking
    # them costs one 6x6 solve instead of two 3x3 ones and changes nothing. 3-vector
    # arithmetic on floats: a numpy call per operation would cost several times more.
    R = R_base.tolist()
    ex, ey, ez = _yaw_error(yaw_des, R)
    wx, wy, wz = omega_world.tolist()
    kp, kd = g.trunk_kp_rot, g.trunk_kd_rot
    acc_rot = (
        kp[0] * ex - kd[0] * wx,
        kp[1] * ey - kd[1] * wy,
        kp[2] * ez + kd[2] * (yaw_rate_des - wz),
    )
    vb = v[:3].tolist()
    v_world = [r[0] * vb[0] + r[1] * vb[1] + r[2] * vb[2] for r in R]
    kp, kd = g.trunk_kp_pos, g.trunk_kd_pos
    acc_pos = [
        kp[i] * (pd - qi) + kd[i] * (vd - vw)
        for i, (pd, qi, vd, vw) in enumerate(
            zip(p_base_des.tolist(), q[:3].tolist(), v_base_des.tolist(), v_world, strict=True)
        )
    ]
    tasks.append(AccelerationTask(J_base, dJv_base, np.array([*acc_pos, *acc_rot])))
    swings = [k for k in range(2) if not stance[k]][: len(swing)]
    n_hand = sum(J.shape[0] for J in J_hands)
    n = 5 * len(swings) + n_hand
    J2 = np.empty((n, nv))
    b2 = np.empty(n)
    a2 = np.empty(n)
    r = 0
    for (p_d, v_d, a_d, yaw_d), k in zip(swing, swings, strict=False):
        Rf = R_feet[k].tolist()
        vf = v_feet[k].tolist()
        sw_kp, sw_kd = g.swing_kp, g.swing_kd
        acc = [
            a + sw_kp * (pd - p) + sw_kd * (vd - vv)
            for a, pd, p, vd, vv in zip(
                a_d.tolist(), p_d.tolist(), p_feet[k].tolist(), v_d.tolist(), vf, strict=False
            )
        ]
        # Angular error and rate in the foot frame; only its y and z rows are tasks.
        e = _yaw_error(yaw_d, Rf)
        for j in (1, 2):
            col = [Rf[0][j], Rf[1][j], Rf[2][j]]
            e_j = col[0] * e[0] + col[1] * e[1] + col[2] * e[2]
            w_j = col[0] * vf[3] + col[1] * vf[4] + col[2] * vf[5]
            acc.append(g.swing_kp_rot * e_j - g.swing_kd_rot * w_j)
        a2[r : r + 5] = acc
        _line_foot_rows(J_feet[k], dJv_feet[k], R_feet[k], J2[r : r + 5], b2[r : r + 5])
        r += 5
    for J, dJv, acc_h in zip(J_hands, dJv_hands, hand_acc, strict=True):
        kh = J.shape[0]
        J2[r : r + kh] = J
        b2[r : r + kh] = dJv
        a2[r : r + kh] = acc_h
        r += kh
    if n:
        tasks.append(AccelerationTask(J2, b2, a2))
    return tasks
