"""Whole-body control: prioritised task accelerations and the paper's WBC QP.

Step 1 (Kim et al. 2019, null-space projection): the commanded joint-space acceleration
qdd_cmd satisfies, in order of priority, the stance contacts (J_c qdd + Jdot_c v = 0), the
trunk orientation and position PD tasks, then swing feet and hands. Each task is solved in the
null space of the ones above with a damped pseudo-inverse (a k x k Cholesky, cheaper than an
SVD at 1 kHz).

Step 2 (the paper's WBC QP): relax the floating-base accelerations (delta_b, 6) and the MPC's
contact wrenches (delta_w, 5 per stance foot in the foot's yaw frame) so that the six
unactuated rows of M (qdd_cmd + [delta_b; 0]) + h = S' tau + J_c' W (u + delta_w) + tau_ext
hold, with the contact constraints on u + delta_w and the torque limits on the n actuated
rows (linear in the same variables). Relaxing the base accelerations is cheap and the wrench
relaxation is expensive, so the MPC's forces lead and the PD tasks shape the joint motion.
All quantities in pinocchio's convention: v = [v_base (body frame), omega_base (body frame),
qdot (n)] for the robot's n joints (HECTOR 16, H1 19), Jacobians LOCAL_WORLD_ALIGNED (see
`locoplan.robot.pinocchio_model`).

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

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt

from locoplan.control import wbc_kernels as _kernels
from locoplan.control.contact import ContactLimits, wrench5_to_world, wrench_rows
from locoplan.control.qp import LeanDenseQp, QpProblem, QpSettings, QpSolver

FloatArray = npt.NDArray[np.float64]

NV_BASE = 6
# Damping (in the task's units squared: m^2 or rad^2 per rad^2) of every level's pseudo-inverse
# in `prioritized_acceleration`. A damped least-squares step J' (J J' + lambda I)^-1 r maps
# a task error of size |r| through a singular value sigma with gain sigma / (sigma^2 +
# lambda) <= 1 / (2 sqrt(lambda)): 500 at this 1e-6, 16 at 1e-3. Where a level is (nearly)
# rank-deficient in the null space of the levels above it (a swing foot's 4-6 rows on a
# 5-DoF leg, a hand near full reach), 1e-6 commands 1000-15000 rad/s^2 of the joints, which
# the WBC QP then relaxes against the torque limits (envelope seed 5150: arm and leg
# relaxations over 500 rad/s^2 in each of four failed runs looked at; seed 9191
# standing-hold-011: one tick's QP failed on it and commanded 12x a shoulder's limit).
# 1e-3 raised envelope seed 5150 from 167 to 175 of 200 (dynamic) and from 170 to 182
# (quasi-static). It was held back while an object 0.9 m away (tests/test_manipulation.py)
# was then "picked": the arms, no longer stalled at full stretch, drew the trunk 0.44 m
# towards it (11 cm down) and dragged the box. The plan now refuses a grasp out of the arms'
# reach (locoplan.plan.payload.check_grasp_reach), so that run is never simulated; the
# envelope figures at 1e-3 on a seed not used before are in the README.
TASK_DAMPING = 1e-3
TORQUE_MARGIN = 1e-5  # N m inside the limits for the joint-relaxed QP's torque rows


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


def prioritized_acceleration(
    tasks: list[AccelerationTask], nv: int, damping: float = TASK_DAMPING
) -> FloatArray:
    """qdd (nv,) satisfying `tasks` in priority order (task 0 highest), each in the null space
    of the tasks above it.

    With N_0 = I and, for task i, JN = J_i N_i, G = JN JN' + damping I:
    qdd += JN' G^-1 (xdd_des - jdot_v - J_i qdd) and N_{i+1} = N_i - JN' G^-1 JN, computed by
    the compiled `wbc_kernels.prioritized` (Cholesky G = L L', W = L^-1 JN:
    JN' G^-1 r = W' L^-1 r and JN' G^-1 JN = W'W). Non-finite task data give NaNs."""
    if not tasks:
        return np.zeros(nv)
    J = np.concatenate([t.J for t in tasks], axis=0)
    r = np.concatenate([np.asarray(t.xdd_des) - np.asarray(t.jdot_v) for t in tasks])
    ends = np.cumsum([t.J.shape[0] for t in tasks]).astype(np.int64)
    return prioritized_rows(J, r, ends, damping)


def prioritized_rows(
    J: FloatArray, r: FloatArray, ends: npt.NDArray[np.int64], damping: float = TASK_DAMPING
) -> FloatArray:
    """`prioritized_acceleration` on stacked rows: J (n, nv), r = xdd_des - Jdot v (n,), and
    the end row of each priority level (ends[-1] == n)."""
    try:
        return np.asarray(
            _kernels.prioritized(
                np.ascontiguousarray(J, dtype=np.float64),
                np.ascontiguousarray(r, dtype=np.float64),
                np.ascontiguousarray(ends, dtype=np.int64),
                float(damping),
            )
        )
    except np.linalg.LinAlgError:
        # Not positive definite: cannot happen with finite data and damping > 0.
        return np.full(J.shape[1], np.nan)


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
    # When no contact wrench meets the torque limits for the commanded joint accelerations,
    # relax those too (weight per (rad/s^2)^2) instead of applying unrelaxed torques; 0 turns
    # it off (see `WholeBodyQp.relaxed_problem`). Cheap on purpose, 100x below the base's:
    # at 1 or 10 the QP bought the torque limits with base acceleration instead, and the
    # robot reaching for an out-of-reach box fell at 0.75 s; at 1e-3 it stands.
    weight_joint: float = 1e-3


@dataclass(frozen=True, slots=True)
class StanceContact:
    """A stance foot for the WBC: its 6 x nv sole Jacobian (LOCAL_WORLD_ALIGNED), the foot's
    yaw (rad) and the MPC's wrench w5 = [Fx', Fy', Fz, My', Mz'] in the foot's yaw frame."""

    J: FloatArray
    yaw: float
    w5: FloatArray

    @staticmethod
    def from_world(J: FloatArray, yaw: float, wrench_world: FloatArray) -> StanceContact:
        """The contact for a world wrench [F; M] (6,) at the sole (`wrench_world_to_w5`)."""
        return StanceContact(J, yaw, wrench_world_to_w5(yaw, wrench_world))


def wrench_world_to_w5(yaw: float, wrench_world: FloatArray) -> FloatArray:
    """w5 = [R_z' F; (R_z' M)_y, (R_z' M)_z] (5,) of a world wrench [F; M] (6,) at a sole
    with yaw rotation R_z (the moment about the foot's long axis is dropped: a line foot
    cannot take it)."""
    c, s = math.cos(yaw), math.sin(yaw)
    fx, fy, fz, mx, my, mz = wrench_world.tolist()
    return np.array([c * fx + s * fy, c * fy - s * fx, fz, c * my - s * mx, mz])


@dataclass(frozen=True, slots=True)
class WbcOutput:
    """Joint torques (n,), the applied contact wrenches w5 per stance foot, the base
    acceleration relaxation (6,), QP status, build and solve times (s), and the joint
    acceleration relaxation (n,) when the QP had to relax those too (status
    "solved_relaxed_joints", see `WholeBodyQp.relaxed_problem`), else None."""

    tau: FloatArray
    w5: tuple[FloatArray, ...]
    delta_base: FloatArray
    ok: bool
    status: str
    iterations: int
    build_time_s: float
    solve_time_s: float
    delta_joint: FloatArray | None = None


class _Workspace:
    """What the reduced QP needs for one number of stance feet `nc` (m = 5 nc variables):
    the wrench weights and the solver."""

    def __init__(self, nc: int, s: WbcSettings) -> None:
        w = np.tile([s.weight_force] * 3 + [s.weight_moment] * 2, nc)
        self.H_w = np.diag(2.0 * w)
        # Bounds met to 1e-9 (N, N m): the reduced QP's optimum then equals the full QP's to
        # well below the generic path's own accuracy (eps_abs 1e-6). DAQP needed at most 3
        # iterations on the recorded ticks; max_iter 200 only stops a runaway.
        self.qp = LeanDenseQp(QpSettings(eps_abs=1e-9, max_iter=200))


class WholeBodyQp:
    """The paper's WBC QP; holds the solvers (and buffers per number of stance feet) across
    ticks."""

    def __init__(self, tau_limits: FloatArray, settings: WbcSettings | None = None) -> None:
        self.settings = settings or WbcSettings()
        # A writable copy: a read-only array would be another argument type to the compiled
        # kernels (one more compilation).
        self.tau_limits = np.array(tau_limits, dtype=float)
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

    def relaxed_problem(
        self,
        M: FloatArray,
        h: FloatArray,
        qdd_cmd: FloatArray,
        stance: list[StanceContact],
        tau_ext: FloatArray,
    ) -> tuple[QpProblem, FloatArray, FloatArray]:
        """`full_problem` with the joint accelerations relaxed as well: x = [delta_b (6);
        delta_w (5 per stance foot); delta_qdd (nj)], cost weight `weight_joint` on
        delta_qdd, tau_full(x) = a + B x with B's last nj columns M[:, 6:].

        Why (beyond the paper, whose QP relaxes only the base accelerations and the wrenches):
        the joint rows of qdd_cmd are fixed there, so when the torques they need exceed the
        limits for every admissible wrench the QP has no solution, and applying the
        unrelaxed torques (then clipping them) is what happened: 8x the hip-roll limit in
        the loaded turn of scenarios/pick-walk-drop.yaml. With delta_qdd free the torque
        rows can always be met (M's joint block is positive definite), so this QP is
        feasible whenever the contact rows are; the tasks are then tracked as well as the
        actuators allow."""
        problem, a, B = self.full_problem(M, h, qdd_cmd, stance, tau_ext)
        nv = M.shape[0]
        nj = nv - NV_BASE
        n0 = problem.n
        n = n0 + nj
        B2 = np.zeros((nv, n))
        B2[:, :n0] = B
        B2[:, n0:] = M[:, NV_BASE:]
        H = np.zeros((n, n))
        H[:n0, :n0] = problem.H
        H[n0:, n0:] = 2.0 * self.settings.weight_joint * np.eye(nj)
        assert problem.C is not None and problem.l is not None and problem.u is not None
        C = np.zeros((problem.C.shape[0], n))
        C[:, :n0] = problem.C
        C[:nj] = B2[NV_BASE:]
        # Torque rows pulled in by 1e-5 N m: the solver meets bounds to its eps_abs (1e-6),
        # and a torque a hair over its limit would count as a clip.
        lo, hi = problem.l.copy(), problem.u.copy()
        lo[:nj] += TORQUE_MARGIN
        hi[:nj] -= TORQUE_MARGIN
        relaxed = QpProblem(H=H, g=np.zeros(n), A=B2[:NV_BASE], b=problem.b, C=C, l=lo, u=hi)
        return relaxed, a, B2

    def _solve_relaxed(
        self,
        M: FloatArray,
        h: FloatArray,
        qdd_cmd: FloatArray,
        stance: list[StanceContact],
        tau_ext: FloatArray,
    ) -> WbcOutput | None:
        """`relaxed_problem` solved; None when it has no solution either."""
        out = self._solve_full(M, h, qdd_cmd, stance, tau_ext, relax_joints=True)
        return replace(out, status="solved_relaxed_joints") if out.ok else None

    def _relax_if_infeasible(
        self,
        out: WbcOutput,
        M: FloatArray,
        h: FloatArray,
        qdd_cmd: FloatArray,
        stance: list[StanceContact],
        tau_ext: FloatArray,
    ) -> WbcOutput:
        if out.ok or out.status != "primal_infeasible" or self.settings.weight_joint <= 0.0:
            return out
        relaxed = self._solve_relaxed(M, h, qdd_cmd, stance, tau_ext)
        return out if relaxed is None else relaxed

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
        weight through the hands, J_e' F_ext). When that QP has no solution, the one with the
        joint accelerations relaxed too (`relaxed_problem`) answers instead."""
        nv = M.shape[0]
        if stance:
            Jc = np.concatenate([c.J for c in stance], axis=0)
            w5 = np.concatenate([c.w5 for c in stance])
        else:
            Jc, w5 = np.zeros((0, nv)), np.zeros(0)
        yaws = np.array([c.yaw for c in stance], dtype=float)
        return self._solve(M, h, qdd_cmd, Jc, yaws, w5, tau_ext, stance)

    def solve_arrays(
        self,
        M: FloatArray,
        h: FloatArray,
        qdd_cmd: FloatArray,
        Jc: FloatArray,
        yaws: FloatArray,
        w5: FloatArray,
        tau_ext: FloatArray,
    ) -> WbcOutput:
        """`solve` for the control loop: the stance feet as stacked arrays, sole Jacobians
        Jc (6 nc, nv), foot yaws (nc,) and MPC wrenches w5 (5 nc,)."""
        return self._solve(M, h, qdd_cmd, Jc, yaws, w5, tau_ext, None)

    def _solve(
        self,
        M: FloatArray,
        h: FloatArray,
        qdd_cmd: FloatArray,
        Jc: FloatArray,
        yaws: FloatArray,
        w5: FloatArray,
        tau_ext: FloatArray,
        stance: list[StanceContact] | None,
    ) -> WbcOutput:
        nc = yaws.shape[0]
        out = None
        if self.settings.lean and nc:
            out = self._solve_lean(M, h, qdd_cmd, Jc, yaws, w5, tau_ext)
            if out is not None and (out.ok or out.status != "primal_infeasible"):
                return out
        if stance is None:
            stance = [
                StanceContact(Jc[6 * i : 6 * i + 6], float(yaws[i]), w5[5 * i : 5 * i + 5])
                for i in range(nc)
            ]
        if out is None:
            out = self._solve_generic(M, h, qdd_cmd, stance, tau_ext)
        return self._relax_if_infeasible(out, M, h, qdd_cmd, stance, tau_ext)

    def _solve_generic(
        self,
        M: FloatArray,
        h: FloatArray,
        qdd_cmd: FloatArray,
        stance: list[StanceContact],
        tau_ext: FloatArray,
    ) -> WbcOutput:
        return self._solve_full(M, h, qdd_cmd, stance, tau_ext, relax_joints=False)

    def _solve_full(
        self,
        M: FloatArray,
        h: FloatArray,
        qdd_cmd: FloatArray,
        stance: list[StanceContact],
        tau_ext: FloatArray,
        relax_joints: bool,
    ) -> WbcOutput:
        """`full_problem` (or `relaxed_problem`) through the generic solver; without a
        solution, no relaxation at all (x = 0)."""
        t0 = time.perf_counter()
        build = self.relaxed_problem if relax_joints else self.full_problem
        problem, a, B = build(M, h, qdd_cmd, stance, tau_ext)
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
            delta_joint=x[NV_BASE + 5 * nc :].copy() if relax_joints else None,
        )

    def _workspace(self, nc: int) -> _Workspace:
        ws = self._ws.get(nc)
        if ws is None:
            ws = _Workspace(nc, self.settings)
            self._ws[nc] = ws
        return ws

    def _solve_lean(
        self,
        M: FloatArray,
        h: FloatArray,
        qdd_cmd: FloatArray,
        Jc: FloatArray,
        yaws: FloatArray,
        w5: FloatArray,
        tau_ext: FloatArray,
    ) -> WbcOutput | None:
        """The reduced QP (module docstring), built by the compiled
        `wbc_kernels.lean_build`, which also returns its unconstrained minimiser:
        `LeanDenseQp.solve_x` takes that when it meets every bound (iterations 0), else DAQP
        solves. None when the generic path must take over."""
        t0 = time.perf_counter()
        nc = yaws.shape[0]
        ws = self._workspace(nc)
        f64 = np.float64
        try:
            H, g, C, lo, hi, tau0, K, Y0, y, found = _kernels.lean_build(
                np.ascontiguousarray(M, dtype=f64),
                np.ascontiguousarray(h, dtype=f64),
                np.ascontiguousarray(qdd_cmd, dtype=f64),
                np.ascontiguousarray(tau_ext, dtype=f64),
                np.ascontiguousarray(Jc, dtype=f64),
                np.ascontiguousarray(yaws, dtype=f64),
                np.ascontiguousarray(w5, dtype=f64),
                self.settings.weight_base,
                ws.H_w,
                self._C5,
                self._lo5,
                self._hi5,
                self.tau_limits,
            )
        except np.linalg.LinAlgError:
            return None
        if found < 0:
            return None
        t1 = time.perf_counter()
        y, status, iterations = ws.qp.solve_x(H, g, C, lo, hi, x_unconstrained=y)
        if status in ("max_iterations", "numerical_error"):
            return None
        ok = status == "solved"
        if ok:
            tau, delta_base = _kernels.lean_finish(tau0, C, K, Y0, y)
            w5_out = tuple(w5[5 * i : 5 * i + 5] + y[5 * i : 5 * i + 5] for i in range(nc))
        else:
            # As the generic path: no relaxation at all (delta_b = 0, delta_w = 0), i.e. the
            # joint rows of a = tau0 + M_jb Y0.
            tau = tau0 + M[NV_BASE:, :NV_BASE].dot(Y0)
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
