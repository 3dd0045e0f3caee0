"""Compiled kernels of the condensed multi-contact MPC (numba, `cache=True`).

Why compiled: one MPC update built its QP and the least-distance form with some 300 numpy
and LAPACK calls on arrays of a few dozen numbers (0.6 ms of the 0.75 ms update on the
recorded walk-square inputs); compiled, that arithmetic takes a few tens of microseconds.
`locoplan.control.mpc_terms` keeps the Python API and fixes the array layouts;
`locoplan.control.mpc` calls both.

The Hessian in semi-separable form. With cnt_k = N - k and C_i, E_k of `mpc_terms`, for
k >= l the step-pair kernel of `mpc_terms` is a term of k plus a term of k times one of l:

    K_omega[k, l] = P_k + V_k E_l,     K_pdot[k, l] = diag(alpha_k - l beta_k),
    P_k = cnt_k Q_omega + dt^2 sum_{i >= k} (C_i - E_k)' Q_Theta C_i,
    V_k = -dt^2 sum_{i >= k} (C_i - E_k)' Q_Theta,
    alpha_k = cnt_k q_v + dt^2 q_p (s2_k + k s1_k),   beta_k = dt^2 q_p s1_k,
    s1_k = sum_{j < cnt_k} (j + 1/2) = cnt_k^2 / 2,   s2_k = sum_{j < cnt_k} (j + 1/2)^2,

so H[k, l] = Phi_k' K[k, l] Phi_l = Lam_k Gam_l' (k >= l) with the 10 x 12 generators
Lam_k = [A_k' P_k, A_k' V_k, B_k' diag(alpha_k), -B_k' diag(beta_k)] and
Gam_l = [A_l', A_l' E_l', B_l', l B_l'], A and B the omega and pdot rows of Phi. The
Hessian is one (n x 12) (12 x n) product (BLAS) whose block-lower part is mirrored, instead
of N^2 small kernel products; its Cholesky factor has the same structure (`factor`).

Kernels use numpy's error model: a division by zero gives inf or nan, as the numpy code they
replace did, instead of raising. Array conventions: float64 and C-contiguous (the callers in
`mpc_terms` and `mpc` make sure: another layout or dtype would compile a second
specialisation at run time), bool masks, int64 indices. Variable layout: per stance (step
k, foot f) the five foot-frame wrench components [Fx', Fy', Fz, My', Mz'], index
10 k + 5 f + a in the full layout; the QP takes the stance ones (``cols``) ordered by step
from N-1 down to 0.

The first call of each kernel compiles it (7-10 s for all of them on this machine, once per
machine: the machine code is cached next to this file in __pycache__, then loading it takes
0.2 s); tests/test_mpc_kernels.py calls every kernel.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from numba import njit

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]

GRAVITY = 9.81


@njit(cache=True, error_model="numpy")
def yaw_terms(
    dt: float, q: FloatArray, yaw_lin: FloatArray, Ib: FloatArray
) -> tuple[
    FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray
]:
    """Per-step terms that depend only on the linearisation yaws, ``q`` (15,) and I_body.

    Returns RzT (N, 3, 3) = R_z(yaw_k)', C (N, 3, 3) = sum_{j <= k} RzT_j,
    E (N, 3, 3) = C_k - RzT_k / 2, Iinv (N, 3, 3) = R_z I_body^-1 R_z', P and V (N, 3, 3),
    alpha and beta (N, 3) of the module docstring. The sums over i >= k run backwards
    without cancellation: with D_k = sum_{i >= k} (C_i - E_k)' Q C_i,
    F_k = sum_{i >= k} (C_i - E_k)' Q, S_k = sum_{i >= k} Q C_i and
    E_{k+1} - E_k = (RzT_k + RzT_{k+1}) / 2 =: M_k,
    D_k = D_{k+1} + RzT_k' Q C_k / 2 + M_k' S_{k+1} and
    F_k = F_{k+1} + RzT_k' Q / 2 + (N - k - 1) M_k' Q.
    """
    N = yaw_lin.shape[0]
    RzT = np.zeros((N, 3, 3))
    C = np.zeros((N, 3, 3))
    E = np.zeros((N, 3, 3))
    Iinv = np.zeros((N, 3, 3))
    P = np.zeros((N, 3, 3))
    V = np.zeros((N, 3, 3))
    alpha = np.zeros((N, 3))
    beta = np.zeros((N, 3))
    Ib_inv = np.empty((3, 3))
    _inv3(Ib, Ib_inv)
    T = np.empty((3, 3))
    for k in range(N):
        c, s = math.cos(yaw_lin[k]), math.sin(yaw_lin[k])
        RzT[k, 0, 0] = c
        RzT[k, 0, 1] = s
        RzT[k, 1, 0] = -s
        RzT[k, 1, 1] = c
        RzT[k, 2, 2] = 1.0
        for a in range(3):
            for b in range(3):
                prev = C[k - 1, a, b] if k > 0 else 0.0
                C[k, a, b] = prev + RzT[k, a, b]
                E[k, a, b] = C[k, a, b] - 0.5 * RzT[k, a, b]
        # Iinv = RzT' Ib_inv RzT.
        for a in range(3):
            for b in range(3):
                acc = 0.0
                for j in range(3):
                    acc += Ib_inv[a, j] * RzT[k, j, b]
                T[a, b] = acc
        for a in range(3):
            for b in range(3):
                acc = 0.0
                for j in range(3):
                    acc += RzT[k, j, a] * T[j, b]
                Iinv[k, a, b] = acc
    dt2 = dt * dt
    D = np.zeros((3, 3))
    F = np.zeros((3, 3))
    S = np.zeros((3, 3))  # S_{k+1}
    M = np.empty((3, 3))
    for k in range(N - 1, -1, -1):
        cnt = N - k
        for a in range(3):
            for b in range(3):
                M[a, b] = 0.5 * (RzT[k, a, b] + RzT[k + 1, a, b]) if k + 1 < N else 0.0
        for a in range(3):
            for b in range(3):
                # (RzT_k' Q C_k)[a, b] / 2 and (M' S)[a, b]
                acc = 0.0
                for j in range(3):
                    acc += 0.5 * RzT[k, j, a] * q[j] * C[k, j, b] + M[j, a] * S[j, b]
                D[a, b] += acc
                F[a, b] += (0.5 * RzT[k, b, a] + (cnt - 1) * M[b, a]) * q[b]
        for a in range(3):
            for b in range(3):
                S[a, b] += q[a] * C[k, a, b]
                P[k, a, b] = dt2 * D[a, b]
                V[k, a, b] = -dt2 * F[a, b]
            P[k, a, a] += cnt * q[6 + a]
        s1 = 0.5 * cnt * cnt
        s2 = 0.0
        for j in range(cnt):
            s2 += (j + 0.5) * (j + 0.5)
        for a in range(3):
            alpha[k, a] = cnt * q[9 + a] + dt2 * q[3 + a] * (s2 + k * s1)
            beta[k, a] = dt2 * q[3 + a] * s1
    return RzT, C, E, Iinv, P, V, alpha, beta


@njit(cache=True, error_model="numpy")
def _inv3(A: FloatArray, out: FloatArray) -> None:
    """out = A^-1 for a 3 x 3 matrix (adjugate over determinant)."""
    c00 = A[1, 1] * A[2, 2] - A[1, 2] * A[2, 1]
    c01 = A[1, 2] * A[2, 0] - A[1, 0] * A[2, 2]
    c02 = A[1, 0] * A[2, 1] - A[1, 1] * A[2, 0]
    det = A[0, 0] * c00 + A[0, 1] * c01 + A[0, 2] * c02
    inv = 1.0 / det
    out[0, 0] = c00 * inv
    out[1, 0] = c01 * inv
    out[2, 0] = c02 * inv
    out[0, 1] = (A[0, 2] * A[2, 1] - A[0, 1] * A[2, 2]) * inv
    out[1, 1] = (A[0, 0] * A[2, 2] - A[0, 2] * A[2, 0]) * inv
    out[2, 1] = (A[0, 1] * A[2, 0] - A[0, 0] * A[2, 1]) * inv
    out[0, 2] = (A[0, 1] * A[1, 2] - A[0, 2] * A[1, 1]) * inv
    out[1, 2] = (A[0, 2] * A[1, 0] - A[0, 0] * A[1, 2]) * inv
    out[2, 2] = (A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]) * inv


@njit(cache=True, error_model="numpy")
def step_terms(
    dt: float,
    x0: FloatArray,
    p_lever: FloatArray,
    contact: BoolArray,
    p_feet: FloatArray,
    foot_yaw: FloatArray,
    yaw_lin: FloatArray,
    mass: float,
    Ib: FloatArray,
    Iinv_body: FloatArray,
    object_held: BoolArray,
    object_mass: FloatArray,
    p_object: FloatArray,
    a_object: FloatArray,
    combined: bool,
) -> tuple[
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    FloatArray,
    IntArray,
]:
    """Per-step terms of one problem (see `mpc_terms.StepTerms`).

    ``p_lever`` (N, 3) the CoM (world, m) step k + 1's lever arms are taken from (step 0's
    from x0). ``object_held`` (N,) and ``object_mass`` (N,) (kg): an object of that mass is held at
    step k (it counts where both are set), ``p_object`` (N, 3) its CoM (world, m),
    ``a_object`` (N, 3) its planned acceleration (world, m/s^2; Model 2 only),
    ``Iinv_body`` (N, 3, 3) R_z I_body^-1 R_z' (`yaw_terms`).
    ``combined``: Model 1 (trunk and object one rigid body about their joint CoM), else Model
    2 (the object's weight as a known external wrench). Returns Iinv (N, 3, 3), mass (N,),
    tau_ext and f_ext (N, 3) (zero without a held object), Tw (N, 2, 3, 5), cos_foot and
    sin_foot (N, 2), Phi (N, 6, 10) and cols (n,) of `mpc_terms.StepTerms`.
    """
    N = p_lever.shape[0]
    Iinv = np.empty((N, 3, 3))
    mass_k = np.empty(N)
    tau_ext = np.zeros((N, 3))
    f_ext = np.zeros((N, 3))
    Tw = np.zeros((N, 2, 3, 5))
    cos_f = np.empty((N, 2))
    sin_f = np.empty((N, 2))
    Phi = np.zeros((N, 6, 10))
    lever = np.empty(3)
    Iw = np.empty((3, 3))
    T = np.empty((3, 3))
    n_st = 0
    for k in range(N):
        for f in range(2):
            if contact[k, f]:
                n_st += 1
    for k in range(N):
        # p_com: x0's CoM for step 0, p_lever[k - 1] after.
        if k == 0:
            pc0, pc1, pc2 = x0[3], x0[4], x0[5]
        else:
            pc0, pc1, pc2 = p_lever[k - 1, 0], p_lever[k - 1, 1], p_lever[k - 1, 2]
        m_o = object_mass[k] if object_held[k] else 0.0
        lever[0], lever[1], lever[2] = pc0, pc1, pc2
        mass_k[k] = mass
        for a in range(3):
            for b in range(3):
                Iinv[k, a, b] = Iinv_body[k, a, b]
        if m_o > 0.0:
            if combined:
                m_t = mass + m_o
                h0 = (mass * pc0 + m_o * p_object[k, 0]) / m_t
                h1 = (mass * pc1 + m_o * p_object[k, 1]) / m_t
                h2 = (mass * pc2 + m_o * p_object[k, 2]) / m_t
                dc0, dc1, dc2 = pc0 - h0, pc1 - h1, pc2 - h2
                do0, do1, do2 = p_object[k, 0] - h0, p_object[k, 1] - h1, p_object[k, 2] - h2
                # I_world = R_z I_body R_z' plus both point masses about the joint CoM.
                cy, sy = math.cos(yaw_lin[k]), math.sin(yaw_lin[k])
                for a in range(3):
                    for b in range(3):
                        T[a, b] = 0.0
                # T = I_body R_z'
                for a in range(3):
                    T[a, 0] = Ib[a, 0] * cy - Ib[a, 1] * sy
                    T[a, 1] = Ib[a, 0] * sy + Ib[a, 1] * cy
                    T[a, 2] = Ib[a, 2]
                for b in range(3):
                    Iw[0, b] = cy * T[0, b] - sy * T[1, b]
                    Iw[1, b] = sy * T[0, b] + cy * T[1, b]
                    Iw[2, b] = T[2, b]
                dcc = dc0 * dc0 + dc1 * dc1 + dc2 * dc2
                doo = do0 * do0 + do1 * do1 + do2 * do2
                dc = (dc0, dc1, dc2)
                do = (do0, do1, do2)
                for a in range(3):
                    for b in range(3):
                        pm = -mass * dc[a] * dc[b] - m_o * do[a] * do[b]
                        if a == b:
                            pm += mass * dcc + m_o * doo
                        Iw[a, b] += pm
                _inv3(Iw, Iinv[k])
                mass_k[k] = m_t
                lever[0], lever[1], lever[2] = h0, h1, h2
            else:
                # What the held object does to the hands: m_o (g - a_o), its weight and its
                # inertia along the planned path (a loaded turn swings it round the trunk).
                fx = -m_o * a_object[k, 0]
                fy = -m_o * a_object[k, 1]
                fz = -m_o * (GRAVITY + a_object[k, 2])
                f_ext[k, 0] = fx
                f_ext[k, 1] = fy
                f_ext[k, 2] = fz
                # tau = (p_object - p_com) x f
                rx = p_object[k, 0] - pc0
                ry = p_object[k, 1] - pc1
                rz = p_object[k, 2] - pc2
                tau_ext[k, 0] = ry * fz - rz * fy
                tau_ext[k, 1] = rz * fx - rx * fz
                tau_ext[k, 2] = rx * fy - ry * fx
        kv = dt / mass_k[k]
        for f in range(2):
            c, s = math.cos(foot_yaw[k, f]), math.sin(foot_yaw[k, f])
            cos_f[k, f] = c
            sin_f[k, f] = s
            rx = p_feet[k, f, 0] - lever[0]
            ry = p_feet[k, f, 1] - lever[1]
            rz = p_feet[k, f, 2] - lever[2]
            # Torque of a unit foot-frame wrench: r x e1', r x e2', r x e3, e2', e3 with
            # e1' = (c, s, 0), e2' = (-s, c, 0).
            W = Tw[k, f]
            W[0, 0] = -rz * s
            W[1, 0] = rz * c
            W[2, 0] = rx * s - ry * c
            W[0, 1] = -rz * c
            W[1, 1] = -rz * s
            W[2, 1] = rx * c + ry * s
            W[0, 2] = ry
            W[1, 2] = -rx
            W[0, 3] = -s
            W[1, 3] = c
            W[2, 4] = 1.0
            if not contact[k, f]:
                continue
            base = 5 * f
            for i in range(3):
                for a in range(5):
                    acc = 0.0
                    for b in range(3):
                        acc += Iinv[k, i, b] * W[b, a]
                    Phi[k, i, base + a] = dt * acc
            Phi[k, 3, base] = kv * c
            Phi[k, 4, base] = kv * s
            Phi[k, 3, base + 1] = -kv * s
            Phi[k, 4, base + 1] = kv * c
            Phi[k, 5, base + 2] = kv
    # Stance variables in the QP's order: steps N-1 down to 0. Step 0's last: only they depend
    # on the measured state (the lever arms from x0's CoM), so the leading block of H repeats
    # while the plan does; and in this order the factor of H has the structure of `factor`.
    cols = np.empty(5 * n_st, dtype=np.int64)
    j = 0
    for k in range(N - 1, -1, -1):
        for f in range(2):
            if contact[k, f]:
                for a in range(5):
                    cols[j + a] = 10 * k + 5 * f + a
                j += 5
    return Iinv, mass_k, tau_ext, f_ext, Tw, cos_f, sin_f, Phi, cols


@njit(cache=True, error_model="numpy")
def propagate(
    x0: FloatArray,
    RzT: FloatArray,
    Iinv: FloatArray,
    mass: FloatArray,
    tau: FloatArray,
    force: FloatArray,
    dt: float,
) -> FloatArray:
    """Exact ZOH rollout x_1..x_N (N, 15) of the SRBD under known per-step wrenches (see
    `mpc_terms.propagate`; ``tau`` and ``force`` (N, 3), zeros where none)."""
    N = RzT.shape[0]
    X = np.empty((N, 15))
    w = np.empty(3)
    v = np.empty(3)
    th = np.empty(3)
    p = np.empty(3)
    aw = np.empty(3)
    av = np.empty(3)
    for i in range(3):
        w[i] = x0[6 + i]
        v[i] = x0[9 + i]
        th[i] = x0[i]
        p[i] = x0[3 + i]
    for k in range(N):
        for i in range(3):
            aw[i] = dt * (
                Iinv[k, i, 0] * tau[k, 0] + Iinv[k, i, 1] * tau[k, 1] + Iinv[k, i, 2] * tau[k, 2]
            )
            av[i] = dt * (force[k, i] / mass[k] + x0[12 + i])
        # Mean omega and velocity over the step, then the new ones.
        m0 = w[0] + 0.5 * aw[0]
        m1 = w[1] + 0.5 * aw[1]
        m2 = w[2] + 0.5 * aw[2]
        for i in range(3):
            th[i] += dt * (RzT[k, i, 0] * m0 + RzT[k, i, 1] * m1 + RzT[k, i, 2] * m2)
            p[i] += dt * (v[i] + 0.5 * av[i])
            w[i] += aw[i]
            v[i] += av[i]
            X[k, i] = th[i]
            X[k, 3 + i] = p[i]
            X[k, 6 + i] = w[i]
            X[k, 9 + i] = v[i]
            X[k, 12 + i] = x0[12 + i]
    return X


@njit(cache=True, error_model="numpy")
def condensed(
    dt: float,
    q: FloatArray,
    r_foot: FloatArray,
    Phi: FloatArray,
    cols: IntArray,
    C: FloatArray,
    E: FloatArray,
    P: FloatArray,
    V: FloatArray,
    alpha: FloatArray,
    beta: FloatArray,
    x_free: FloatArray,
    x_ref: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """(H, g, Lam, Gam) of the condensed QP over the stance variables ``cols`` (QP order).

    H (n, n) = G'QG + R from the generators Lam and Gam (n, 12, a row per variable) of the
    module docstring (one BLAS product, then the block-lower part mirrored), ``r_foot``
    (10,) R's diagonal per step. g = G'Q(x_free -
    x_ref) as g_k = Phi_k' lambda_k with the adjoint lambda from suffix sums (see
    `mpc_terms`); ``x_free`` (N, 15) the rollout without contact wrenches.
    """
    N = Phi.shape[0]
    n = cols.shape[0]
    Lam = np.empty((n, 12))
    Gam = np.empty((n, 12))
    steps = np.empty(n, dtype=np.int64)
    for j in range(n):
        k = cols[j] // 10
        c = cols[j] % 10
        steps[j] = k
        a0, a1, a2 = Phi[k, 0, c], Phi[k, 1, c], Phi[k, 2, c]
        b0, b1, b2 = Phi[k, 3, c], Phi[k, 4, c], Phi[k, 5, c]
        for i in range(3):
            Lam[j, i] = P[k, 0, i] * a0 + P[k, 1, i] * a1 + P[k, 2, i] * a2
            Lam[j, 3 + i] = V[k, 0, i] * a0 + V[k, 1, i] * a1 + V[k, 2, i] * a2
            Gam[j, 3 + i] = E[k, i, 0] * a0 + E[k, i, 1] * a1 + E[k, i, 2] * a2
        Gam[j, 0], Gam[j, 1], Gam[j, 2] = a0, a1, a2
        Lam[j, 6], Lam[j, 7], Lam[j, 8] = alpha[k, 0] * b0, alpha[k, 1] * b1, alpha[k, 2] * b2
        Lam[j, 9], Lam[j, 10], Lam[j, 11] = -beta[k, 0] * b0, -beta[k, 1] * b1, -beta[k, 2] * b2
        Gam[j, 6], Gam[j, 7], Gam[j, 8] = b0, b1, b2
        Gam[j, 9], Gam[j, 10], Gam[j, 11] = k * b0, k * b1, k * b2
    H = np.dot(Lam, Gam.T)
    # H[i, j] = Lam_i . Gam_j holds where step_i > step_j, or within a step where i >= j
    # (the columns of one step are contiguous and ascending): mirror it onto the other side.
    for i in range(n):
        si = steps[i]
        for j in range(i):
            if si >= steps[j]:
                H[j, i] = H[i, j]
            else:
                H[i, j] = H[j, i]
        H[i, i] += r_foot[cols[i] % 10]
    # Gradient: the adjoint of the prediction, per step.
    Z = np.empty((N, 12))
    for k in range(N):
        qe = np.empty(12)
        for i in range(12):
            qe[i] = q[i] * (x_free[k, i] - x_ref[k, i])
        for i in range(3):
            Z[k, i] = qe[6 + i] + dt * (
                C[k, 0, i] * qe[0] + C[k, 1, i] * qe[1] + C[k, 2, i] * qe[2]
            )
            Z[k, 3 + i] = qe[i]
            Z[k, 6 + i] = qe[9 + i] + dt * k * qe[3 + i]
            Z[k, 9 + i] = qe[3 + i]
    lam = np.empty((N, 6))
    SZ = np.zeros(12)
    for k in range(N - 1, -1, -1):
        for i in range(12):
            SZ[i] += Z[k, i]
        for i in range(3):
            lam[k, i] = SZ[i] - dt * (E[k, 0, i] * SZ[3] + E[k, 1, i] * SZ[4] + E[k, 2, i] * SZ[5])
            lam[k, 3 + i] = SZ[6 + i] - dt * (k - 0.5) * SZ[9 + i]
    g = np.empty(n)
    for j in range(n):
        k = cols[j] // 10
        c = cols[j] % 10
        acc = 0.0
        for i in range(6):
            acc += Phi[k, i, c] * lam[k, i]
        g[j] = acc
    return H, g, Lam, Gam


@njit(cache=True, error_model="numpy")
def finish(
    U_foot: FloatArray,
    Tw: FloatArray,
    cos_f: FloatArray,
    sin_f: FloatArray,
    tau_ext: FloatArray,
    f_ext: FloatArray,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """From the foot-frame wrenches U_foot (N, 2, 5): U (N, 2, 5) with the forces in the
    world ([Fx, Fy, Fz, My', Mz']), and the torque (N, 3) about the lever origin and the force
    (N, 3) on the body per step, external wrench included."""
    N = U_foot.shape[0]
    U = np.empty((N, 2, 5))
    tau = np.empty((N, 3))
    force = np.empty((N, 3))
    for k in range(N):
        for i in range(3):
            tau[k, i] = tau_ext[k, i]
            force[k, i] = f_ext[k, i]
        for f in range(2):
            u = U_foot[k, f]
            c, s = cos_f[k, f], sin_f[k, f]
            U[k, f, 0] = c * u[0] - s * u[1]
            U[k, f, 1] = s * u[0] + c * u[1]
            U[k, f, 2] = u[2]
            U[k, f, 3] = u[3]
            U[k, f, 4] = u[4]
            for i in range(3):
                force[k, i] += U[k, f, i]
                acc = 0.0
                for a in range(5):
                    acc += Tw[k, f, i, a] * u[a]
                tau[k, i] += acc
    return U, tau, force


# --- least-distance form: a structured Cholesky factor of H --------------------------------
#
# In the QP's order (steps from N-1 down to 0, a block of 5 or 10 variables per step in
# stance), between a block a and an earlier block b step(a) < step(b), so
# H[a, b] = X_a Y_b' with the row generator X = Gam and the column generator Y = Lam (n x 12
# each, a row per variable). The Cholesky factor then has L[a, b] = X_a Z_b' below the
# diagonal blocks, with, block by block,
#     S_b  = sum_{c before b} Z_c' Z_c                  (12 x 12)
#     L_bb L_bb' = H[b, b] - X_b S_b X_b'              (dense Cholesky of <= 10 x 10)
#     Z_b  = L_bb^-1 (Y_b - X_b S_b)                    (n_b x 12)
# -- O(N) small products instead of a dense O(n^3) factorisation, and solves in O(n).


@njit(cache=True, error_model="numpy")
def factor_blocks(cols: IntArray) -> tuple[IntArray, IntArray]:
    """(start, size) of each step's block of variables, in the QP's order."""
    n = cols.shape[0]
    n_blocks = 0
    for j in range(n):
        if j == 0 or cols[j] // 10 != cols[j - 1] // 10:
            n_blocks += 1
    start = np.empty(n_blocks, dtype=np.int64)
    size = np.zeros(n_blocks, dtype=np.int64)
    b = -1
    for j in range(n):
        if j == 0 or cols[j] // 10 != cols[j - 1] // 10:
            b += 1
            start[b] = j
        size[b] += 1
    return start, size


@njit(cache=True, error_model="numpy")
def factor(
    H: FloatArray, X: FloatArray, Y: FloatArray, start: IntArray, size: IntArray
) -> tuple[FloatArray, FloatArray, bool]:
    """The structured Cholesky factor of H (see above): (L_diag, Z, ok) with L_diag (n, 10)
    holding each diagonal block's lower factor in its rows (columns 0..n_b-1) and Z (n, 12).
    ok is False when H is not (numerically) positive definite."""
    n = H.shape[0]
    L_diag = np.zeros((n, 10))
    Z = np.zeros((n, 12))
    S = np.zeros((12, 12))
    XS = np.empty((10, 12))
    for b in range(start.shape[0]):
        r0 = start[b]
        nb = size[b]
        # XS = X_b S
        for i in range(nb):
            for a in range(12):
                XS[i, a] = 0.0
            for c in range(12):
                x = X[r0 + i, c]
                if x != 0.0:
                    for a in range(12):
                        XS[i, a] += x * S[c, a]
        # Lower part of H_bb - X_b S X_b', then its Cholesky factor in place.
        for i in range(nb):
            for j in range(i + 1):
                acc = H[r0 + i, r0 + j]
                for a in range(12):
                    acc -= XS[i, a] * X[r0 + j, a]
                L_diag[r0 + i, j] = acc
        for j in range(nb):
            d = L_diag[r0 + j, j]
            for p in range(j):
                d -= L_diag[r0 + j, p] * L_diag[r0 + j, p]
            if not d > 0.0:
                return L_diag, Z, False
            d = math.sqrt(d)
            L_diag[r0 + j, j] = d
            for i in range(j + 1, nb):
                acc = L_diag[r0 + i, j]
                for p in range(j):
                    acc -= L_diag[r0 + i, p] * L_diag[r0 + j, p]
                L_diag[r0 + i, j] = acc / d
        # Z_b = L_bb^-1 (Y_b - X_b S), then S += Z_b' Z_b.
        for i in range(nb):
            inv = 1.0 / L_diag[r0 + i, i]
            for a in range(12):
                acc = Y[r0 + i, a] - XS[i, a]
                for p in range(i):
                    acc -= L_diag[r0 + i, p] * Z[r0 + p, a]
                Z[r0 + i, a] = acc * inv
        for i in range(nb):
            for a in range(12):
                z = Z[r0 + i, a]
                for c in range(12):
                    S[a, c] += z * Z[r0 + i, c]
    return L_diag, Z, True


@njit(cache=True, error_model="numpy")
def factor_solve(
    rhs: FloatArray,
    X: FloatArray,
    L_diag: FloatArray,
    Z: FloatArray,
    start: IntArray,
    size: IntArray,
) -> FloatArray:
    """H^-1 rhs (n,) from the factor of `factor` (forward then backward substitution)."""
    n = rhs.shape[0]
    nb_all = start.shape[0]
    z = np.empty(n)
    s = np.zeros(12)
    for b in range(nb_all):
        r0 = start[b]
        nb = size[b]
        for i in range(nb):
            acc = rhs[r0 + i]
            for a in range(12):
                acc -= X[r0 + i, a] * s[a]
            for p in range(i):
                acc -= L_diag[r0 + i, p] * z[r0 + p]
            z[r0 + i] = acc / L_diag[r0 + i, i]
        for i in range(nb):
            for a in range(12):
                s[a] += Z[r0 + i, a] * z[r0 + i]
    x = np.empty(n)
    t = np.zeros(12)
    for b in range(nb_all - 1, -1, -1):
        r0 = start[b]
        nb = size[b]
        for i in range(nb - 1, -1, -1):
            acc = z[r0 + i]
            for a in range(12):
                acc -= Z[r0 + i, a] * t[a]
            for p in range(i + 1, nb):
                acc -= L_diag[r0 + p, i] * x[r0 + p]
            x[r0 + i] = acc / L_diag[r0 + i, i]
        for i in range(nb):
            for a in range(12):
                t[a] += X[r0 + i, a] * x[r0 + i]
    return x


@njit(cache=True, error_model="numpy")
def dense_factor(
    X: FloatArray, L_diag: FloatArray, Z: FloatArray, start: IntArray, size: IntArray
) -> FloatArray:
    """The factor as a dense lower-triangular (n, n) C-contiguous array."""
    n = X.shape[0]
    L = np.dot(X, Z.T)
    for b in range(start.shape[0]):
        r0 = start[b]
        nb = size[b]
        for i in range(r0, r0 + nb):
            for j in range(r0, i + 1):
                L[i, j] = L_diag[i, j - r0]
            for j in range(i + 1, n):
                L[i, j] = 0.0
    return L


@njit(cache=True, error_model="numpy")
def constraint_rows(U: FloatArray, rows: FloatArray, box: IntArray, idx: IntArray) -> FloatArray:
    """Rows ``idx`` of W = [U[box]; C U] for an upper-triangular, C-contiguous U (n, n) and C
    block-diagonal: ``rows`` (R, 5) per foot-step of five consecutive variables, i.e.
    W[n_b + R f + r] = rows[r] @ U[5 f : 5 f + 5] (n_b = len(box)); every index in ``idx``
    below n_b + (n / 5) R. Each row is written once, from column 5 f on (U is zero below its
    diagonal); a row of ``rows`` with at most two nonzeros (all of the wrench rows) takes one
    pass over the two rows of U it combines."""
    n = U.shape[0]
    R = rows.shape[0]
    n_b = box.shape[0]
    # Each wrench row's nonzeros: how many, and the first two (column, weight).
    nnz = np.zeros(R, dtype=np.int64)
    col = np.zeros((R, 2), dtype=np.int64)
    wt = np.zeros((R, 2))
    for r in range(R):
        for a in range(5):
            if rows[r, a] != 0.0:
                if nnz[r] < 2:
                    col[r, nnz[r]] = a
                    wt[r, nnz[r]] = rows[r, a]
                nnz[r] += 1
    W = np.empty((idx.shape[0], n))
    for k in range(idx.shape[0]):
        j = idx[k]
        Wr = W[k]
        if j < n_b:
            q = box[j]
            Wr[:q] = 0.0
            Wr[q:] = U[q, q:]
            continue
        f = (j - n_b) // R
        r = (j - n_b) - R * f
        c0 = 5 * f
        Wr[:c0] = 0.0
        if nnz[r] == 0:
            Wr[c0:] = 0.0
        elif nnz[r] == 1:
            u1 = U[c0 + col[r, 0]]
            w1 = wt[r, 0]
            for c in range(c0, n):
                Wr[c] = w1 * u1[c]
        elif nnz[r] == 2:
            u1 = U[c0 + col[r, 0]]
            u2 = U[c0 + col[r, 1]]
            w1 = wt[r, 0]
            w2 = wt[r, 1]
            for c in range(c0, n):
                Wr[c] = w1 * u1[c] + w2 * u2[c]
        else:
            for c in range(c0, n):
                acc = 0.0
                for a in range(5):
                    acc += rows[r, a] * U[c0 + a, c]
                Wr[c] = acc
    return W


_warm = False


def warm_up() -> None:
    """Compile (or load from the cache) every kernel for the argument types the MPC passes,
    on a tiny well-posed problem, once per process: `MultiContactMpc` calls it when it is
    built, so that no MPC update compiles (7-10 s without the cache, 0.2 s to load it)."""
    global _warm
    if _warm:
        return
    N, dt = 2, 0.03
    q = np.ones(15)
    yaw = np.zeros(N)
    Ib = np.eye(3)
    RzT, C, E, Iinv, P, V, alpha, beta = yaw_terms(dt, q, yaw, Ib)
    x0 = np.zeros(15)
    x0[5] = 0.5
    x0[14] = -GRAVITY
    x_ref = np.ascontiguousarray(np.tile(x0, (N, 1)))
    p_feet = np.zeros((N, 2, 3))
    p_feet[:, 0, 1] = 0.1
    p_feet[:, 1, 1] = -0.1
    Iinv_k, mass, tau, force, Tw, c, s, Phi, cols = step_terms(
        dt,
        x0,
        np.ascontiguousarray(x_ref[:, 3:6]),
        np.ones((N, 2), dtype=np.bool_),
        p_feet,
        np.zeros((N, 2)),
        yaw,
        10.0,
        Ib,
        Iinv,
        np.zeros(N, dtype=np.bool_),
        np.zeros(N),
        np.zeros((N, 3)),
        np.zeros((N, 3)),
        False,
    )
    X = propagate(x0, RzT, Iinv_k, mass, tau, force, dt)
    H, g, Lam, Gam = condensed(dt, q, np.ones(10), Phi, cols, C, E, P, V, alpha, beta, X, x_ref)
    start, size = factor_blocks(cols)
    L_diag, Z, _ = factor(H, Gam, Lam, start, size)
    factor_solve(-g, Gam, L_diag, Z, start, size)
    n = cols.shape[0]
    dense_factor(Gam, L_diag, Z, start, size)
    constraint_rows(
        np.eye(n), np.ones((2, 5)), np.arange(2, n, 5, dtype=np.int64), np.arange(3, dtype=np.int64)
    )
    finish(np.zeros((N, 2, 5)), Tw, c, s, tau, force)
    _warm = True
