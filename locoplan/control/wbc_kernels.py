"""Compiled kernels of the whole-body controller's tick (numba, `cache=True`).

Why compiled: one WBC tick stacks about 30 task rows over 22 velocity columns, projects three
priority levels and builds a 10-variable QP. As numpy calls that was some 150 calls of a few
microseconds each, 115-170 us per tick; compiled it is a few microseconds of arithmetic. The
Python API (`locoplan.control.tasks.build_tasks`, `locoplan.control.wbc`) keeps the same
meaning and calls these kernels; the formulas are documented there. Cholesky factors come
from LAPACK (`np.linalg.cholesky`); triangular solves of at most 16 x 16 are written out.

Array conventions (float64, C-contiguous, shapes fixed by the caller):
- Jacobians LOCAL_WORLD_ALIGNED (rows: linear then angular velocity in world axes), nv
  columns (22 for HECTOR);
- a line foot's task rows: the three linear rows, then the angular rows about the foot's own
  y and z axes (roll about its long axis is not controllable by the 5-DoF leg);
- the reduced QP's variable: delta_w (5 per stance foot, foot yaw frame), see `lean_build`.

The first call of each kernel compiles it (about 10 s for all of them, once per machine: the
machine code is cached next to this file in __pycache__).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from numba import njit

from locoplan.control import qp

FloatArray = npt.NDArray[np.float64]

NV_BASE = 6

# Gains packed for `stack_tasks`: trunk kp_pos (3), kd_pos (3), kp_rot (3), kd_rot (3), then
# swing kp, kd, kp_rot, kd_rot.
N_GAINS = 16


@njit(cache=True)
def yaw_error(yaw: float, R: FloatArray) -> tuple[float, float, float]:
    """World rotation vector e with exp([e]x) R = R_z(yaw) (log map of E = R_z(yaw) R')."""
    return yaw_pitch_error(yaw, 0.0, R)


@njit(cache=True)
def yaw_pitch_error(yaw: float, pitch: float, R: FloatArray) -> tuple[float, float, float]:
    """World rotation vector e with exp([e]x) R = R_z(yaw) R_y(pitch) (log map of
    E = R_z(yaw) R_y(pitch) R'); pitch < 0 is the trunk's nose up (ZYX angles)."""
    c, s = math.cos(yaw), math.sin(yaw)
    cp, sp = math.cos(pitch), math.sin(pitch)
    # D = R_z(yaw) R_y(pitch) = [[c cp, -s, c sp], [s cp, c, s sp], [-sp, 0, cp]];
    # E = D R': E[i, j] = sum_k D[i, k] R[j, k] (only the entries the log map needs).
    d00, d01, d02 = c * cp, -s, c * sp
    d10, d11, d12 = s * cp, c, s * sp
    d20, d22 = -sp, cp
    e00 = d00 * R[0, 0] + d01 * R[0, 1] + d02 * R[0, 2]
    e11 = d10 * R[1, 0] + d11 * R[1, 1] + d12 * R[1, 2]
    e22 = d20 * R[2, 0] + d22 * R[2, 2]
    e01 = d00 * R[1, 0] + d01 * R[1, 1] + d02 * R[1, 2]
    e10 = d10 * R[0, 0] + d11 * R[0, 1] + d12 * R[0, 2]
    e02 = d00 * R[2, 0] + d01 * R[2, 1] + d02 * R[2, 2]
    e20 = d20 * R[0, 0] + d22 * R[0, 2]
    e12 = d10 * R[2, 0] + d11 * R[2, 1] + d12 * R[2, 2]
    e21 = d20 * R[1, 0] + d22 * R[1, 2]
    cos_t = max(-1.0, min(1.0, (e00 + e11 + e22 - 1.0) / 2.0))
    theta = math.acos(cos_t)
    f = 0.5 if theta < 1e-6 else theta / (2.0 * math.sin(theta))
    return f * (e21 - e12), f * (e02 - e20), f * (e10 - e01)


@njit(cache=True)
def line_foot_rows(
    J: FloatArray, dJv: FloatArray, R_foot: FloatArray, J_out: FloatArray, b_out: FloatArray
) -> None:
    """Write the 5 controllable rows of a line foot's Jacobian J (6, nv) and drift dJv (6,)
    into J_out (5, nv) and b_out (5,)."""
    nv = J.shape[1]
    for i in range(3):
        for c in range(nv):
            J_out[i, c] = J[i, c]
        b_out[i] = dJv[i]
    for j in range(2):
        a0, a1, a2 = R_foot[0, j + 1], R_foot[1, j + 1], R_foot[2, j + 1]
        for c in range(nv):
            J_out[3 + j, c] = a0 * J[3, c] + a1 * J[4, c] + a2 * J[5, c]
        b_out[3 + j] = a0 * dJv[3] + a1 * dJv[4] + a2 * dJv[5]


@njit(cache=True)
def stack_tasks(
    gains: FloatArray,
    q: FloatArray,
    v: FloatArray,
    R_base: FloatArray,
    omega_world: FloatArray,
    p_base_des: FloatArray,
    v_base_des: FloatArray,
    yaw_des: float,
    pitch_des: float,
    yaw_rate_des: float,
    J_base: FloatArray,
    dJv_base: FloatArray,
    stance: npt.NDArray[np.bool_],
    J_feet: FloatArray,
    dJv_feet: FloatArray,
    v_feet: FloatArray,
    p_feet: FloatArray,
    R_feet: FloatArray,
    n_swing: int,
    swing_pva: FloatArray,
    swing_yaw: FloatArray,
    J_hands: FloatArray,
    dJv_hands: FloatArray,
    hand_acc: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, npt.NDArray[np.int64]]:
    """All task rows in priority order: (J (n, nv), Jdot v (n,), commanded xdd (n,), the end
    row of each priority level). Shapes: J_feet (2, 6, nv), dJv_feet / v_feet (2, 6),
    p_feet (2, 3), R_feet (2, 3, 3), swing_pva (2, 3, 3) rows position / velocity /
    acceleration of the first `n_swing` swinging feet in foot order, swing_yaw (2,),
    J_hands (nh, 3, nv), dJv_hands and hand_acc (nh, 3)."""
    nv = J_base.shape[1]
    n_st = 0
    for k in range(2):
        if stance[k]:
            n_st += 1
    swings = np.empty(2, dtype=np.int64)
    n_sw = 0
    for k in range(2):
        if not stance[k] and n_sw < n_swing:
            swings[n_sw] = k
            n_sw += 1
    nh = J_hands.shape[0]
    n = 5 * n_st + 6 + 5 * n_sw + 3 * nh
    J = np.empty((n, nv))
    b = np.empty(n)
    a = np.zeros(n)
    ends = np.empty(3, dtype=np.int64)
    n_levels = 0
    r = 0
    # Level 0: stance contacts, J_c qdd + Jdot_c v = 0.
    for k in range(2):
        if stance[k]:
            line_foot_rows(J_feet[k], dJv_feet[k], R_feet[k], J[r : r + 5], b[r : r + 5])
            r += 5
    if r > 0:
        ends[n_levels] = r
        n_levels += 1
    # Level 1: trunk position and orientation PD (the base's 6 DoF are independent).
    ex, ey, ez = yaw_pitch_error(yaw_des, pitch_des, R_base)
    wx, wy, wz = omega_world[0], omega_world[1], omega_world[2]
    for i in range(3):
        vw = R_base[i, 0] * v[0] + R_base[i, 1] * v[1] + R_base[i, 2] * v[2]
        a[r + i] = gains[i] * (p_base_des[i] - q[i]) + gains[3 + i] * (v_base_des[i] - vw)
    a[r + 3] = gains[6] * ex - gains[9] * wx
    a[r + 4] = gains[7] * ey - gains[10] * wy
    a[r + 5] = gains[8] * ez + gains[11] * (yaw_rate_des - wz)
    for i in range(6):
        for c in range(nv):
            J[r + i, c] = J_base[i, c]
        b[r + i] = dJv_base[i]
    r += 6
    ends[n_levels] = r
    n_levels += 1
    # Level 2: swing feet (position, foot pitch and yaw) and hands.
    sw_kp, sw_kd, sw_kp_rot, sw_kd_rot = gains[12], gains[13], gains[14], gains[15]
    for j in range(n_sw):
        k = swings[j]
        for i in range(3):
            a[r + i] = (
                swing_pva[j, 2, i]
                + sw_kp * (swing_pva[j, 0, i] - p_feet[k, i])
                + sw_kd * (swing_pva[j, 1, i] - v_feet[k, i])
            )
        ex, ey, ez = yaw_error(swing_yaw[j], R_feet[k])
        Rf = R_feet[k]
        for jj in range(2):
            c0, c1, c2 = Rf[0, jj + 1], Rf[1, jj + 1], Rf[2, jj + 1]
            e_j = c0 * ex + c1 * ey + c2 * ez
            w_j = c0 * v_feet[k, 3] + c1 * v_feet[k, 4] + c2 * v_feet[k, 5]
            a[r + 3 + jj] = sw_kp_rot * e_j - sw_kd_rot * w_j
        line_foot_rows(J_feet[k], dJv_feet[k], Rf, J[r : r + 5], b[r : r + 5])
        r += 5
    for hh in range(nh):
        for i in range(3):
            for c in range(nv):
                J[r + i, c] = J_hands[hh, i, c]
            b[r + i] = dJv_hands[hh, i]
            a[r + i] = hand_acc[hh, i]
        r += 3
    if r > ends[n_levels - 1]:
        ends[n_levels] = r
        n_levels += 1
    return J, b, a, ends[:n_levels].copy()


@njit(cache=True)
def _forward_sub(L: npt.NDArray[np.floating], B: FloatArray) -> FloatArray:
    """L^-1 B for lower-triangular L (k, k) and B (k, p)."""
    k, p = B.shape
    X = np.empty((k, p))
    for i in range(k):
        inv = 1.0 / L[i, i]
        for c in range(p):
            s = B[i, c]
            for j in range(i):
                s -= L[i, j] * X[j, c]
            X[i, c] = s * inv
    return X


@njit(cache=True)
def _back_sub_t(L: npt.NDArray[np.floating], B: FloatArray) -> FloatArray:
    """L'^-1 B for lower-triangular L (k, k) and B (k, p)."""
    k, p = B.shape
    X = np.empty((k, p))
    for i in range(k - 1, -1, -1):
        inv = 1.0 / L[i, i]
        for c in range(p):
            s = B[i, c]
            for j in range(i + 1, k):
                s -= L[j, i] * X[j, c]
            X[i, c] = s * inv
    return X


@njit(cache=True)
def _all_finite(A: FloatArray) -> bool:
    # An explicit loop: numba compiles it without the temporary np.isfinite(A) would make.
    for x in A.ravel():  # noqa: SIM110
        if not math.isfinite(x):
            return False
    return True


@njit(cache=True)
def prioritized(
    J: FloatArray, r: FloatArray, ends: npt.NDArray[np.int64], damping: float
) -> FloatArray:
    """qdd (nv,) meeting the task levels J[start:end] qdd = r[start:end] in priority order
    (Kim et al. 2019), each in the null space of the levels above, damped pseudo-inverses.

    With N_0 = I and, per level, JN = J N, G = JN JN' + damping I = L L' (Cholesky),
    W = L^-1 JN: qdd += W' L^-1 (r - J qdd) and N -= W'W. Non-finite data give NaNs (G is
    positive definite otherwise, damping > 0)."""
    nv = J.shape[1]
    qdd = np.zeros(nv)
    if not (_all_finite(J) and _all_finite(r)):
        return np.full(nv, np.nan)
    N = np.eye(nv)
    start = 0
    last = ends.shape[0] - 1
    for li in range(ends.shape[0]):
        end = ends[li]
        k = end - start
        Jl = np.ascontiguousarray(J[start:end])
        rl = r[start:end] - Jl.dot(qdd)
        JN = Jl if li == 0 else Jl.dot(N)
        G = JN.dot(JN.T)
        for i in range(k):
            G[i, i] += damping
        L = np.linalg.cholesky(G)
        W = _forward_sub(L, JN)
        z = np.ascontiguousarray(_forward_sub(L, rl.reshape(k, 1))[:, 0])
        qdd += z.dot(W)
        if li < last:
            N -= np.ascontiguousarray(W.T).dot(W)
        start = end
    return qdd


@njit(cache=True)
def lean_build(
    M: FloatArray,
    h: FloatArray,
    qdd_cmd: FloatArray,
    tau_ext: FloatArray,
    Jc: FloatArray,
    yaws: FloatArray,
    w5: FloatArray,
    weight_base: float,
    H_w: FloatArray,
    C5: FloatArray,
    lo5: FloatArray,
    hi5: FloatArray,
    tau_limits: FloatArray,
) -> tuple[
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    int,
]:
    """The WBC's reduced QP over delta_w (m = 5 nc) for stance feet with sole Jacobians
    Jc (6 nc, nv), yaws (nc,) and MPC wrenches w5 (m,) (`locoplan.control.wbc` docstring):

    a = M qdd_cmd + h - tau_ext - (J'W) w5; delta_b = -Y0 + K delta_w with
    [Y0, K] = M_bb^-1 [a_b, (J'W)_b]; H = 2 w_b K'K + H_w, g = -2 w_b K'Y0; rows
    C = [M_jb K - (J'W)_j; blockdiag(C5)] with l = [-tau_lim; lo5...] - shift,
    u = [tau_lim; hi5...] - shift, shift = [tau0; C5 w5_i], tau0 = a_j - M_jb Y0.

    Returns (H, g, C, l, u, tau0, K, Y0, y, status): y is the unconstrained minimiser
    -H^-1 g (`qp.LeanDenseQp.solve_x` takes it as the solution when it meets every row);
    status 1, or -1 when the data are not finite."""
    nv = M.shape[0]
    nj = nv - NV_BASE
    nc = yaws.shape[0]
    m = 5 * nc
    rc = C5.shape[0]
    nrow = nj + rc * nc
    H = np.zeros((m, m))
    g = np.zeros(m)
    C = np.zeros((nrow, m))
    lo = np.empty(nrow)
    hi = np.empty(nrow)
    tau0 = np.empty(nj)
    K = np.zeros((NV_BASE, m))
    Y0 = np.zeros(NV_BASE)
    y = np.zeros(m)
    if not (_all_finite(M) and _all_finite(h) and _all_finite(qdd_cmd) and _all_finite(Jc)):
        return H, g, C, lo, hi, tau0, K, Y0, y, -1
    # J'W (nv, m): generalised force of delta_w; W maps w5 (yaw frame) to the world wrench.
    JtW = np.empty((nv, m))
    for i in range(nc):
        cy, sy = math.cos(yaws[i]), math.sin(yaws[i])
        r, k = 6 * i, 5 * i
        for c in range(nv):
            j0, j1 = Jc[r, c], Jc[r + 1, c]
            JtW[c, k] = cy * j0 + sy * j1
            JtW[c, k + 1] = -sy * j0 + cy * j1
            JtW[c, k + 2] = Jc[r + 2, c]
            JtW[c, k + 3] = -sy * Jc[r + 3, c] + cy * Jc[r + 4, c]
            JtW[c, k + 4] = Jc[r + 5, c]
    a = M.dot(qdd_cmd) + h - tau_ext - JtW.dot(w5)
    # [Y0, K] = M_bb^-1 [a_b, (J'W)_b] by Cholesky (M_bb is symmetric positive definite).
    Mbb = np.ascontiguousarray(M[:NV_BASE, :NV_BASE])
    rhs = np.empty((NV_BASE, 1 + m))
    rhs[:, 0] = a[:NV_BASE]
    rhs[:, 1:] = JtW[:NV_BASE]
    Lb = np.linalg.cholesky(Mbb)
    Y = _back_sub_t(Lb, _forward_sub(Lb, rhs))
    Y0[:] = Y[:, 0]
    K[:, :] = Y[:, 1:]
    wb2 = 2.0 * weight_base
    Kt = np.ascontiguousarray(K.T)
    H[:, :] = wb2 * Kt.dot(K) + H_w
    g[:] = -wb2 * Kt.dot(Y0)
    # Joint rows: tau_j = tau0 + (M_jb K - (J'W)_j) delta_w.
    Q = np.ascontiguousarray(M[NV_BASE:, :NV_BASE]).dot(Y)
    for j in range(nj):
        tau0[j] = a[NV_BASE + j] - Q[j, 0]
        for c in range(m):
            C[j, c] = Q[j, 1 + c] - JtW[NV_BASE + j, c]
        lo[j] = -tau_limits[j] - tau0[j]
        hi[j] = tau_limits[j] - tau0[j]
    for i in range(nc):
        for rr in range(rc):
            row = nj + rc * i + rr
            cw = 0.0
            for c in range(5):
                C[row, 5 * i + c] = C5[rr, c]
                cw += C5[rr, c] * w5[5 * i + c]
            lo[row] = lo5[rr] - cw
            hi[row] = hi5[rr] - cw
    # The unconstrained minimiser (the solver checks whether it meets every row).
    LH = np.linalg.cholesky(H)
    y[:] = -_back_sub_t(LH, _forward_sub(LH, g.reshape(m, 1)))[:, 0]
    return H, g, C, lo, hi, tau0, K, Y0, y, 1


@njit(cache=True)
def lean_finish(
    tau0: FloatArray, C: FloatArray, K: FloatArray, Y0: FloatArray, y: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Joint torques tau0 + C_j y (nj,) and the base-acceleration relaxation K y - Y0 (6,)."""
    nj = tau0.shape[0]
    tau = tau0 + C[:nj].dot(y)
    delta_base = K.dot(y) - Y0
    return tau, delta_base


@njit(cache=True)
def wall_rows(
    cols: npt.NDArray[np.intp],
    lower: FloatArray,
    upper: FloatArray,
    q: FloatArray,
    v: FloatArray,
    qdd: FloatArray,
    decel: FloatArray,
    tau: float,
) -> tuple[npt.NDArray[np.intp], FloatArray]:
    """`locoplan.control.controller.joint_wall_rows` with one deceleration per joint: the
    same operations in the same order (a square root, products, quotients), so the same
    values to the bit. Compiled because it runs every control tick: the Python loop cost
    4-5 us a tick inside the loop for HECTOR's two elbows."""
    k = cols.shape[0]
    hit = np.empty(k, dtype=np.intp)
    acc = np.empty(k)
    n = 0
    for i in range(k):
        c = cols[i]
        d = decel[i]
        qj, vj, a = q[c + 1], v[c], qdd[c]
        to_hi = upper[i] - qj
        to_lo = qj - lower[i]
        s_hi = 1.0 if to_hi > 0.0 else (-1.0 if to_hi < 0.0 else 0.0)
        s_lo = 1.0 if to_lo > 0.0 else (-1.0 if to_lo < 0.0 else 0.0)
        v_hi = s_hi * math.sqrt(2.0 * d * abs(to_hi))
        v_lo = -s_lo * math.sqrt(2.0 * d * abs(to_lo))
        a_hi = (v_hi - vj) / tau
        a_lo = (v_lo - vj) / tau
        if a > a_hi:
            hit[n] = c
            acc[n] = a_hi
            n += 1
        elif a < a_lo:
            hit[n] = c
            acc[n] = a_lo
            n += 1
    return hit[:n].copy(), acc[:n].copy()


@njit(cache=True)
def prioritized_walled(
    J: FloatArray,
    a: FloatArray,
    b: FloatArray,
    ends: npt.NDArray[np.int64],
    damping: float,
    cols: npt.NDArray[np.intp],
    lower: FloatArray,
    upper: FloatArray,
    q: FloatArray,
    v: FloatArray,
    decel: FloatArray,
    tau: float,
) -> tuple[FloatArray, npt.NDArray[np.intp], FloatArray]:
    """The task stack's accelerations under the working-range wall in one call: `prioritized`
    on rows J with r = a - b, then `wall_rows` on that qdd, and where it walls joints,
    `prioritized` again on the stack with those joints' rows (a unit row each, r its wall
    acceleration) as the first level. Returns (qdd, walled columns, their accelerations).

    What the controller did with three calls and the stacking in numpy (`LocoManipulation
    Controller._keep_in_working_range`), the same operations in the same order (the wall
    rows' r is acc - 0, as the stacked b's zeros gave), so the same qdd to the bit; one
    call saves the second kernel's dispatch and its boxed results, 2-3 us of a 60 us tick."""
    r = a - b
    qdd = prioritized(J, r, ends, damping)
    hit, acc = wall_rows(cols, lower, upper, q, v, qdd, decel, tau)
    n = hit.shape[0]
    if n == 0:
        return qdd, hit, acc
    rows, nv = J.shape
    Jw = np.zeros((n + rows, nv))
    rw = np.empty(n + rows)
    for i in range(n):
        Jw[i, hit[i]] = 1.0
        rw[i] = acc[i] - 0.0
    Jw[n:] = J
    rw[n:] = r
    ends_w = np.empty(ends.shape[0] + 1, dtype=np.int64)
    ends_w[0] = n
    ends_w[1:] = ends + n
    return prioritized(Jw, rw, ends_w, damping), hit, acc


def warm_up(nv: int) -> None:
    """Compile (or load from the cache) every kernel for the argument types the controller
    passes, on a small well-posed problem, so that the first control tick does not pay for
    the compilation (about 10 s on a machine without the cache)."""
    f64 = np.float64
    eye3 = np.eye(3)
    J = np.zeros((6, nv))
    J[:, :6] = np.eye(6)
    J_feet = np.stack([J, J])
    rows = stack_tasks(
        np.ones(N_GAINS),
        np.zeros(nv + 1),
        np.zeros(nv),
        eye3,
        np.zeros(3),
        np.zeros(3),
        np.zeros(3),
        0.0,
        0.0,
        0.0,
        J.copy(),
        np.zeros(6),
        np.array([True, False]),
        J_feet,
        np.zeros((2, 6)),
        np.zeros((2, 6)),
        np.zeros((2, 3)),
        np.stack([eye3, eye3]),
        1,
        np.zeros((2, 3, 3)),
        np.zeros(2),
        np.ascontiguousarray(J_feet[:, :3]),
        np.zeros((2, 3)),
        np.zeros((2, 3)),
    )
    Jt, b, a, ends = rows
    prioritized(Jt, a - b, ends, 1e-6)
    M = np.eye(nv, dtype=f64)
    C5 = np.zeros((1, 5))
    _, _, C, _, _, tau0, K, Y0, y, _ = lean_build(
        M,
        np.zeros(nv),
        np.zeros(nv),
        np.zeros(nv),
        J.copy(),
        np.zeros(1),
        np.zeros(5),
        0.1,
        np.eye(5),
        C5,
        np.zeros(1),
        np.zeros(1),
        np.ones(nv - NV_BASE),
    )
    lean_finish(tau0, C, K, Y0, y)
    cols = np.array([NV_BASE], dtype=np.intp)
    one = np.ones(1)
    wall_rows(cols, one, one, np.zeros(nv + 1), np.zeros(nv), np.zeros(nv), one, 0.05)
    prioritized_walled(
        Jt, a, b, ends, 1e-6, cols, one, one, np.zeros(nv + 1), np.zeros(nv), one, 0.05
    )
    qp.warm_up()
