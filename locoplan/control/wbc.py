"""Whole-body control: prioritised task accelerations and the paper's WBC QP.

Step 1 (Kim et al. 2019, null-space projection): the commanded joint-space acceleration
qdd_cmd satisfies, in order of priority, the stance contacts (J_c qdd + Jdot_c v = 0), the
trunk orientation and position PD tasks, then swing feet and hands. Each task is solved in the
null space of the ones above with a damped pseudo-inverse (a k x k Cholesky, cheaper than an
SVD at 1 kHz).

Step 2 (the paper's WBC QP): relax the floating-base accelerations (delta_b, 6) and the MPC's
contact wrenches (delta_w, 5 per stance foot in the foot's yaw frame) so that the six
unactuated rows of M (qdd_cmd + [delta_b; 0]) + h = S' tau + J_c' W (u + delta_w) + tau_ext
hold, with the contact constraints on u + delta_w and the torque limits on the 16 actuated
rows (linear in the same variables). Relaxing the base accelerations is cheap and the wrench
relaxation is expensive, so the MPC's forces lead and the PD tasks shape the joint motion.
All quantities in pinocchio's convention: v = [v_base (body frame), omega_base (body frame),
qdot (16)], Jacobians LOCAL_WORLD_ALIGNED (see `locoplan.robot.pinocchio_model`).

How it is solved every tick (`WholeBodyQp.solve`): the six equalities fix delta_b given
delta_w through the base block of M (symmetric positive definite), delta_b = c + K delta_w,
so the QP reduces to one over delta_w alone (5 per stance foot) with inequality rows only:
H_r = 2 (w_b K'K + W_w), g_r = 2 w_b K'c, torque rows (M_jb K - (J'W)_j) delta_w. That QP
has the same optimum as the full one and goes to `qp.LeanDenseQp` (DAQP's dual active-set
method called directly; it returns the unconstrained minimiser at once when that is
feasible). The full QP (`WholeBodyQp.full_problem`) through the generic `QpSolver` remains
the fallback and `WbcSettings(lean=False)` selects it.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import scipy.linalg

from locoplan.control.contact import ContactLimits, wrench5_to_world, wrench_rows
from locoplan.control.qp import LeanDenseQp, QpProblem, QpSettings, QpSolver

FloatArray = npt.NDArray[np.float64]

NV_BASE = 6

_potrf, _potrs, _trtri = scipy.linalg.get_lapack_funcs(
    ("potrf", "potrs", "trtri"), dtype=np.float64
)


@dataclass(frozen=True, slots=True)
class AccelerationTask:
    """xdd = J qdd + Jdot_v, commanded to `xdd_des`; J (k, nv), vectors (k,)."""

    J: FloatArray
    jdot_v: FloatArray
    xdd_des: FloatArray


def damped_pinv(J: FloatArray, damping: float) -> FloatArray:
    """J' (J J' + damping I)^-1, shape (nv, k)."""
    k = J.shape[0]
    G = J @ J.T
    G[np.diag_indices(k)] += damping
    return np.asarray(np.linalg.solve(G, J).T, dtype=np.float64)


@functools.lru_cache(maxsize=64)
def _scaled_identity(k: int, scale: float) -> FloatArray:
    out = scale * np.eye(k)
    out.flags.writeable = False
    return out


def prioritized_acceleration(
    tasks: list[AccelerationTask], nv: int, damping: float = 1e-6
) -> FloatArray:
    """qdd (nv,) satisfying `tasks` in priority order (task 0 highest), each in the null space
    of the tasks above it.

    With N_0 = I and, for task i, JN = J_i N_i, G = JN JN' + damping I:
    qdd += JN' G^-1 (xdd_des - jdot_v - J_i qdd) and N_{i+1} = N_i - JN' G^-1 JN. With
    G = L L' (LAPACK potrf) and W = L^-1 JN (explicit inverse of the k x k factor, trtri):
    JN' G^-1 r = W' L^-1 r and JN' G^-1 JN = W'W, fewer and cheaper calls than triangular
    solves at these sizes. N is not formed for the first task (N_0 = I) nor after the last.
    """
    last = len(tasks) - 1
    qdd = np.zeros(nv)
    N: FloatArray | None = None
    for i, task in enumerate(tasks):
        J = task.J
        k = J.shape[0]
        r = task.xdd_des - task.jdot_v
        if N is None:
            JN = J
        else:
            JN = J.dot(N)
            r -= J.dot(qdd)
        G = JN.dot(JN.T)
        G += _scaled_identity(k, damping)
        # G is symmetric: G.T is the column-major view LAPACK takes without a copy. clean=1
        # zeroes the upper triangle, which the triangular inverse below must not see.
        L, info = _potrf(G.T, lower=1, clean=1, overwrite_a=1)
        if info == 0:
            Linv, info = _trtri(L, lower=1, overwrite_c=1)
        if info != 0:
            # Not positive definite: only with non-finite data (damping > 0). Let the
            # straightforward formula produce the same error or NaNs as before.
            pinv = damped_pinv(JN, damping)
            qdd = qdd + pinv @ r
            if i < last:
                N = (np.eye(nv) if N is None else N) - pinv @ JN
            continue
        # With W = L^-1 JN: JN' G^-1 r = W' (L^-1 r) and JN' G^-1 JN = W'W.
        W = Linv.dot(JN)
        qdd += Linv.dot(r).dot(W)
        if i < last:
            P = W.T.dot(W)
            N = np.subtract(_scaled_identity(nv, 1.0) if N is None else N, P)
    return qdd


@dataclass(frozen=True, slots=True)
class WbcSettings:
    """Weights of the QP relaxations and the solver. Units: delta_b in m/s^2 and rad/s^2,
    delta_w in N and N m. ``lean``: solve the reduced QP with `qp.LeanDenseQp` (default),
    else the full QP through the generic `QpSolver` of ``backend`` (also the fallback when
    the lean path does not finish)."""

    weight_base: float = 0.1
    weight_force: float = 1.0
    weight_moment: float = 10.0
    limits: ContactLimits = field(default_factory=ContactLimits)
    backend: str = "daqp"
    lean: bool = True


@dataclass(frozen=True, slots=True)
class StanceContact:
    """A stance foot for the WBC: its 6 x nv sole Jacobian (LOCAL_WORLD_ALIGNED), the foot's
    yaw (rad) and the MPC's wrench w5 = [Fx', Fy', Fz, My', Mz'] in the foot's yaw frame."""

    J: FloatArray
    yaw: float
    w5: FloatArray

    @staticmethod
    def from_world(J: FloatArray, yaw: float, wrench_world: FloatArray) -> StanceContact:
        """The contact for a world wrench [F; M] (6,) at the sole: w5 = [R_z' F; (R_z' M)_y,
        (R_z' M)_z] with R_z the foot's yaw rotation (the moment about the foot's long axis
        is dropped: a line foot cannot take it)."""
        c, s = math.cos(yaw), math.sin(yaw)
        fx, fy, fz, mx, my, mz = wrench_world.tolist()
        w5 = np.array([c * fx + s * fy, c * fy - s * fx, fz, c * my - s * mx, mz])
        return StanceContact(J, yaw, w5)


@dataclass(frozen=True, slots=True)
class WbcOutput:
    """Joint torques (16,), the applied contact wrenches w5 per stance foot, the base
    acceleration relaxation (6,), QP status, build and solve times (s)."""

    tau: FloatArray
    w5: tuple[FloatArray, ...]
    delta_base: FloatArray
    ok: bool
    status: str
    iterations: int
    build_time_s: float
    solve_time_s: float


class _Workspace:
    """Buffers of the reduced QP for one number of stance feet `nc` (m = 5 nc variables):
    the constant contact rows and bounds, the wrench maps, the stacked Jacobians."""

    def __init__(
        self,
        nc: int,
        tau_limits: FloatArray,
        s: WbcSettings,
        C5: FloatArray,
        lo5: FloatArray,
        hi5: FloatArray,
    ) -> None:
        m = 5 * nc
        nj = tau_limits.shape[0]
        nv = nj + NV_BASE
        rows_c = C5.shape[0]
        self.C = np.zeros((nj + rows_c * nc, m))
        self.C5 = np.zeros((rows_c * nc, m))
        for i in range(nc):
            self.C5[rows_c * i : rows_c * (i + 1), 5 * i : 5 * i + 5] = C5
        self.C[nj:] = self.C5
        # Bounds on the rows: [-tau_limits; contact lo] - shift <= C delta_w <= [tau_limits;
        # contact hi] - shift, shift = [joint torques at delta_w = 0; C5 w5].
        self.lo = np.concatenate([-tau_limits, np.tile(lo5, nc)])
        self.hi = np.concatenate([tau_limits, np.tile(hi5, nc)])
        self.shift = np.empty(self.C.shape[0])
        self.l = np.empty(self.C.shape[0])
        self.u = np.empty(self.C.shape[0])
        w = np.tile([s.weight_force] * 3 + [s.weight_moment] * 2, nc)
        self.H_w = np.diag(2.0 * w)
        # T maps the stacked w5 (m,) to the stacked world wrenches (6 nc,); the entries that
        # depend on the feet's yaw are written every tick.
        self.T = np.zeros((6 * nc, m))
        for i in range(nc):
            self.T[6 * i + 2, 5 * i + 2] = 1.0
            self.T[6 * i + 5, 5 * i + 4] = 1.0
        self.Jc = np.empty((6 * nc, nv))
        self.w5 = np.empty(m)
        self.rhs = np.empty((NV_BASE, 1 + m), order="F")
        # Bounds met to 1e-9 (N, N m): the reduced QP's optimum then equals the full QP's to
        # well below the generic path's own accuracy (eps_abs 1e-6). DAQP needed at most 3
        # iterations on the recorded ticks; max_iter 200 only stops a runaway.
        self.qp = LeanDenseQp(QpSettings(eps_abs=1e-9, max_iter=200))


class WholeBodyQp:
    """The paper's WBC QP; holds the solvers (and buffers per number of stance feet) across
    ticks."""

    def __init__(self, tau_limits: FloatArray, settings: WbcSettings | None = None) -> None:
        self.settings = settings or WbcSettings()
        self.tau_limits = np.asarray(tau_limits, dtype=float)
        self._solver = QpSolver(
            self.settings.backend, QpSettings(eps_abs=1e-6, check_duality_gap=False, max_iter=100)
        )
        self._C5, self._lo5, self._hi5 = wrench_rows(self.settings.limits)
        self._ws: dict[int, _Workspace] = {}

    def full_problem(
        self,
        M: FloatArray,
        h: FloatArray,
        qdd_cmd: FloatArray,
        stance: list[StanceContact],
        tau_ext: FloatArray,
    ) -> tuple[QpProblem, FloatArray, FloatArray]:
        """The full QP over x = [delta_b (6); delta_w (5 per stance foot)] and the affine map
        tau_full(x) = a + B x (a (nv,), B (nv, n)); rows 0..5 of tau_full are its equalities."""
        s = self.settings
        nv = M.shape[0]
        nc = len(stance)
        n = NV_BASE + 5 * nc
        a = M @ qdd_cmd + h - tau_ext
        B = np.zeros((nv, n))
        B[:, :NV_BASE] = M[:, :NV_BASE]
        for i, c in enumerate(stance):
            JtW = c.J.T @ wrench5_to_world(c.yaw)  # (nv, 5)
            a -= JtW @ c.w5
            B[:, NV_BASE + 5 * i : NV_BASE + 5 * i + 5] = -JtW
        w_diag = np.full(n, s.weight_base)
        for i in range(nc):
            k = NV_BASE + 5 * i
            w_diag[k : k + 3] = s.weight_force
            w_diag[k + 3 : k + 5] = s.weight_moment
        H = np.diag(2.0 * w_diag)
        g = np.zeros(n)
        rows_c = self._C5.shape[0]
        nj = nv - NV_BASE
        C = np.zeros((nj + rows_c * nc, n))
        lo = np.empty(C.shape[0])
        hi = np.empty(C.shape[0])
        C[:nj] = B[NV_BASE:]
        lo[:nj] = -self.tau_limits - a[NV_BASE:]
        hi[:nj] = self.tau_limits - a[NV_BASE:]
        for i, c in enumerate(stance):
            r = nj + rows_c * i
            k = NV_BASE + 5 * i
            C[r : r + rows_c, k : k + 5] = self._C5
            cw = self._C5 @ c.w5
            lo[r : r + rows_c] = self._lo5 - cw
            hi[r : r + rows_c] = self._hi5 - cw
        problem = QpProblem(H=H, g=g, A=B[:NV_BASE], b=-a[:NV_BASE], C=C, l=lo, u=hi)
        return problem, a, B

    def solve(
        self,
        M: FloatArray,
        h: FloatArray,
        qdd_cmd: FloatArray,
        stance: list[StanceContact],
        tau_ext: FloatArray,
    ) -> WbcOutput:
        """Torques for M qdd + h = S' tau + sum_i J_i' W_i (w5_i + delta_i) + tau_ext.

        `tau_ext` (nv,) are the other generalised forces acting on the robot (held object's
        weight through the hands, J_e' F_ext)."""
        if self.settings.lean and stance:
            out = self._solve_lean(M, h, qdd_cmd, stance, tau_ext)
            if out is not None:
                return out
        return self._solve_generic(M, h, qdd_cmd, stance, tau_ext)

    def _solve_generic(
        self,
        M: FloatArray,
        h: FloatArray,
        qdd_cmd: FloatArray,
        stance: list[StanceContact],
        tau_ext: FloatArray,
    ) -> WbcOutput:
        t0 = time.perf_counter()
        problem, a, B = self.full_problem(M, h, qdd_cmd, stance, tau_ext)
        t1 = time.perf_counter()
        sol = self._solver.solve(problem)
        x = sol.x if sol.ok else np.zeros(problem.n)
        tau_full = a + B @ x
        nc = len(stance)
        w5 = tuple(stance[i].w5 + x[NV_BASE + 5 * i : NV_BASE + 5 * i + 5] for i in range(nc))
        return WbcOutput(
            tau=tau_full[NV_BASE:],
            w5=w5,
            delta_base=x[:NV_BASE].copy(),
            ok=sol.ok,
            status=sol.status,
            iterations=sol.iterations,
            build_time_s=t1 - t0,
            solve_time_s=time.perf_counter() - t1,
        )

    def _workspace(self, nc: int) -> _Workspace:
        ws = self._ws.get(nc)
        if ws is None:
            ws = _Workspace(nc, self.tau_limits, self.settings, self._C5, self._lo5, self._hi5)
            self._ws[nc] = ws
        return ws

    def _solve_lean(
        self,
        M: FloatArray,
        h: FloatArray,
        qdd_cmd: FloatArray,
        stance: list[StanceContact],
        tau_ext: FloatArray,
    ) -> WbcOutput | None:
        """The reduced QP (module docstring); None when the generic path must take over."""
        t0 = time.perf_counter()
        nv = M.shape[0]
        nc = len(stance)
        ws = self._workspace(nc)
        T, Jc, w5 = ws.T, ws.Jc, ws.w5
        for i, c in enumerate(stance):
            cy, sy = math.cos(c.yaw), math.sin(c.yaw)
            r, k = 6 * i, 5 * i
            T[r, k] = cy
            T[r, k + 1] = -sy
            T[r + 1, k] = sy
            T[r + 1, k + 1] = cy
            T[r + 3, k + 3] = -sy
            T[r + 4, k + 3] = cy
            Jc[r : r + 6] = c.J
            w5[k : k + 5] = c.w5
        JtW = Jc.T.dot(T)  # (nv, m): generalised force of delta_w
        a = M.dot(qdd_cmd)
        a += h
        a -= tau_ext
        a -= JtW.dot(w5)
        # Base rows: M_bb delta_b = -a_b + (J'W)_b delta_w, i.e. delta_b = -Y_0 + K delta_w
        # with [Y_0, K] = M_bb^-1 [a_b, (J'W)_b].
        Lb, info = _potrf(M[:NV_BASE, :NV_BASE], lower=1, clean=0)
        if info != 0:
            return None
        rhs = ws.rhs
        rhs[:, 0] = a[:NV_BASE]
        rhs[:, 1:] = JtW[:NV_BASE]
        Y = _potrs(Lb, rhs, lower=1, overwrite_b=1)[0]
        K = Y[:, 1:]
        wb2 = 2.0 * self.settings.weight_base
        H = K.T.dot(K)
        H *= wb2
        H += ws.H_w
        g = K.T.dot(Y[:, 0])
        g *= -wb2
        # Joint rows: tau_j = a_j - M_jb Y_0 + (M_jb K - (J'W)_j) delta_w.
        Q = M[NV_BASE:, :NV_BASE].dot(Y)
        nj = nv - NV_BASE
        C = ws.C
        np.subtract(Q[:, 1:], JtW[NV_BASE:], out=C[:nj])
        shift = ws.shift
        tau0 = shift[:nj]
        np.subtract(a[NV_BASE:], Q[:, 0], out=tau0)
        ws.C5.dot(w5, out=shift[nj:])
        np.subtract(ws.lo, shift, out=ws.l)
        np.subtract(ws.hi, shift, out=ws.u)
        t1 = time.perf_counter()
        y, status, iterations = ws.qp.solve_x(H, g, C, ws.l, ws.u)
        if status in ("max_iterations", "numerical_error"):
            return None
        ok = status == "solved"
        if ok:
            tau = tau0 + C[:nj].dot(y)
            delta_base = K.dot(y)
            delta_base -= Y[:, 0]
            w5_out = tuple(w5[5 * i : 5 * i + 5] + y[5 * i : 5 * i + 5] for i in range(nc))
        else:
            # As the generic path: no relaxation, x = 0.
            tau = a[NV_BASE:].copy()
            delta_base = np.zeros(NV_BASE)
            w5_out = tuple(w5[5 * i : 5 * i + 5].copy() for i in range(nc))
        return WbcOutput(
            tau=tau,
            w5=w5_out,
            delta_base=delta_base,
            ok=ok,
            status=status,
            iterations=iterations,
            build_time_s=t1 - t0,
            solve_time_s=time.perf_counter() - t1,
        )
