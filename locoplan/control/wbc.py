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
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from locoplan.control.contact import ContactLimits, wrench5_to_world, wrench_rows
from locoplan.control.qp import QpProblem, QpSettings, QpSolver

FloatArray = npt.NDArray[np.float64]

NV_BASE = 6


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
    tasks: list[AccelerationTask], nv: int, damping: float = 1e-6
) -> FloatArray:
    """qdd (nv,) satisfying `tasks` in priority order (task 0 highest), each in the null space
    of the tasks above it."""
    qdd = np.zeros(nv)
    N = np.eye(nv)
    for task in tasks:
        JN = task.J @ N
        JN_pinv = damped_pinv(JN, damping)
        qdd = qdd + JN_pinv @ (task.xdd_des - task.jdot_v - task.J @ qdd)
        N = N - JN_pinv @ JN
    return qdd


@dataclass(frozen=True, slots=True)
class WbcSettings:
    """Weights of the QP relaxations and the solver. Units: delta_b in m/s^2 and rad/s^2,
    delta_w in N and N m."""

    weight_base: float = 0.1
    weight_force: float = 1.0
    weight_moment: float = 10.0
    limits: ContactLimits = field(default_factory=ContactLimits)
    backend: str = "proxsuite"


@dataclass(frozen=True, slots=True)
class StanceContact:
    """A stance foot for the WBC: its 6 x nv sole Jacobian (LOCAL_WORLD_ALIGNED), the foot's
    yaw (rad) and the MPC's wrench w5 = [Fx', Fy', Fz, My', Mz'] in the foot's yaw frame."""

    J: FloatArray
    yaw: float
    w5: FloatArray


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


class WholeBodyQp:
    """The paper's WBC QP; holds the QP solver across ticks."""

    def __init__(self, tau_limits: FloatArray, settings: WbcSettings | None = None) -> None:
        self.settings = settings or WbcSettings()
        self.tau_limits = np.asarray(tau_limits, dtype=float)
        self._solver = QpSolver(
            self.settings.backend, QpSettings(eps_abs=1e-6, check_duality_gap=False, max_iter=100)
        )
        self._C5, self._lo5, self._hi5 = wrench_rows(self.settings.limits)

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
        t0 = time.perf_counter()
        s = self.settings
        nv = M.shape[0]
        nc = len(stance)
        n = NV_BASE + 5 * nc
        # tau_full(x) = a + B x, x = [delta_b; delta_w]; rows 0..5 must vanish.
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
        A_eq = B[:NV_BASE]
        b_eq = -a[:NV_BASE]
        rows_c = self._C5.shape[0]
        C = np.zeros((nv - NV_BASE + rows_c * nc, n))
        lo = np.empty(C.shape[0])
        hi = np.empty(C.shape[0])
        nj = nv - NV_BASE
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
        problem = QpProblem(H=H, g=g, A=A_eq, b=b_eq, C=C, l=lo, u=hi)
        t1 = time.perf_counter()
        sol = self._solver.solve(problem)
        x = sol.x if sol.ok else np.zeros(n)
        tau_full = a + B @ x
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
