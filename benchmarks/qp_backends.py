"""QP backends on the MPC QP and on a WBC-like dense QP: daqp, proxsuite, piqp, and for
reference quadprog when installed. (The hand-written dual active-set method that the MPC
and the WBC's lean path used before daqp is gone; see git history.)

Run: OMP_NUM_THREADS=1 .venv/bin/python benchmarks/qp_backends.py [--n 300]

1. The MPC QP (horizon 20, condensed, foot-frame wrenches): the problems met in the closed
   loops of benchmarks/mpc_qp.py (standing, stepping, standing with 5 kg held; state noise
   level 1), solved in order by one solver per configuration, so re-use of the solver object
   and warm starts count. "least-distance form" is the MPC's path: the form is computed by
   the MPC from the generators of its Hessian (a structured Cholesky factor, and U and W
   when x_u violates a bound), and that computation is included in the time.
2. A dense QP like the whole-body QP: 38 variables, random SPD H, 6 equalities, 30
   two-sided inequalities, a box; consecutive problems differ by a small random change, as
   ticks of a control loop do.

Times in microseconds (wall time: for QpSolver the whole solve call -- scaling,
setup/update and solve), median / p99, iterations median / max, the largest difference from
a piqp reference at eps 1e-10, and failures. "warm": the previous solution's active set (or
proxsuite's previous iterate) when the problem has the same rows.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from locoplan.control.mpc import MpcInput, MpcSettings, MultiContactMpc
from locoplan.control.mpc_terms import propagate, step_terms
from locoplan.control.qp import (
    QpProblem,
    QpSettings,
    QpSolver,
    active_constraint_ids,
)

sys.path.insert(0, str(Path(__file__).resolve().parent))
import mpc_qp

try:  # optional reference: Goldfarb-Idnani in Fortran (pip install quadprog)
    import quadprog
except ImportError:  # pragma: no cover - optional
    quadprog = None


@dataclass
class Case:
    """One solve: time (s), iterations, x (None on failure)."""

    time_s: float
    iterations: int
    x: np.ndarray | None


def wbc_like_problems(count: int, seed: int = 0) -> list[QpProblem]:
    """Consecutive 38-variable QPs: 6 equalities, 30 inequalities, a box."""
    rng = np.random.default_rng(seed)
    n, n_eq, n_in = 38, 6, 30
    M = rng.normal(size=(n, n))
    H0 = M @ M.T / n + 0.1 * np.eye(n)
    A0 = rng.normal(size=(n_eq, n))
    C0 = rng.normal(size=(n_in, n))
    out = []
    for _ in range(count):
        dH = rng.normal(scale=0.01, size=(n, n))
        H = H0 + dH @ dH.T
        A = A0 + rng.normal(scale=0.01, size=A0.shape)
        C = C0 + rng.normal(scale=0.01, size=C0.shape)
        l = np.full(n_in, -1.0)
        l[::3] = -np.inf
        u = np.full(n_in, 1.0)
        out.append(
            QpProblem(
                H=H,
                g=rng.normal(size=n),
                A=A,
                b=rng.normal(scale=0.2, size=n_eq),
                C=C,
                l=l,
                u=u,
                x_lower=np.full(n, -2.0),
                x_upper=np.full(n, 2.0),
            )
        )
    return out


def mpc_inputs(count: int) -> dict[str, list[MpcInput]]:
    """The MPC inputs met in the benchmark closed loops."""
    return {
        "standing": mpc_qp.record_inputs(mpc_qp.standing_contact, count),
        "stepping": mpc_qp.record_inputs(mpc_qp.stepping_contact, count),
        "stand+5kg": mpc_qp.record_inputs(mpc_qp.standing_contact, count, object_mass=5.0),
    }


def qp_solver_runner(backend: str, settings: QpSettings) -> Callable[[list[QpProblem]], list[Case]]:
    def run(problems: list[QpProblem]) -> list[Case]:
        solver = QpSolver(backend, settings)
        solver.solve(problems[0])
        out = []
        for p in problems:
            sol = solver.solve(p)
            out.append(Case(sol.solve_time_s, sol.iterations, sol.x if sol.ok else None))
        return out

    return run


def least_distance_runner(
    inputs: list[MpcInput], warm: bool
) -> Callable[[list[QpProblem]], list[Case]]:
    """daqp on the MPC's least-distance form; the form's computation is timed too."""

    def run(problems: list[QpProblem]) -> list[Case]:
        base = MpcSettings()
        mpc = MultiContactMpc(replace(base, qp=replace(base.qp, warm_start=warm)))
        solver = QpSolver("daqp", mpc.settings.qp)
        out = []
        prev = None
        for p, inp in zip(problems, inputs, strict=True):
            # The Hessian's generators come with the QP's build (not timed here).
            s = mpc.settings
            Ib = np.ascontiguousarray(inp.inertia_body, dtype=np.float64)
            kern = mpc._get_kernel(np.ascontiguousarray(inp.yaw_lin, dtype=np.float64), Ib)
            st = step_terms(inp, s.dt, kern.Iinv, Ib)
            x_free = propagate(inp.x0, kern.RzT, st.Iinv, st.mass, st.tau_ext, st.f_ext, s.dt)
            _, Lam, Gam = mpc._condensed(inp, st, kern, x_free, s.f_min, s.f_max)
            t0 = time.perf_counter()
            # The MPC's own computation (private on purpose).
            form = mpc._least_distance(p, Lam, Gam, st.cols)
            hint = active_constraint_ids(prev) if warm and prev is not None else None
            if hint is not None and prev is not None and prev.x.shape[0] != p.n:
                hint = None
            sol = solver.solve(p, active_hint=hint, least_distance=form)
            out.append(Case(time.perf_counter() - t0, sol.iterations, sol.x if sol.ok else None))
            prev = sol if sol.ok else None
        return out

    return run


def quadprog_runner(problems: list[QpProblem]) -> list[Case]:
    """quadprog.solve_qp (cold; it has no warm start): min 1/2 x'Gx - a'x s.t. C'x >= b, the
    one-sided rows built in the timed call."""
    out = []
    for p in problems:
        t0 = time.perf_counter()
        I = np.eye(p.n)
        rows, rhs = [], []
        lo = p.x_lower if p.x_lower is not None else np.full(p.n, -np.inf)
        hi = p.x_upper if p.x_upper is not None else np.full(p.n, np.inf)
        for M, lower, upper in ((I, lo, hi), (p.C, p.l, p.u)):
            if M is None:
                continue
            lower = lower if lower is not None else np.full(M.shape[0], -np.inf)
            upper = upper if upper is not None else np.full(M.shape[0], np.inf)
            fl, fu = np.isfinite(lower), np.isfinite(upper)
            rows += [M[fl], -M[fu]]
            rhs += [lower[fl], -upper[fu]]
        meq = 0
        if p.A is not None:
            rows.insert(0, p.A)
            rhs.insert(0, p.b)
            meq = p.A.shape[0]
        Cq = np.vstack(rows).T.copy()
        try:
            r = quadprog.solve_qp(p.H, -p.g, Cq, np.concatenate(rhs), meq)
            case = Case(time.perf_counter() - t0, int(r[3][0]), r[0])
        except ValueError:  # quadprog raises on infeasible or non-convex problems
            case = Case(time.perf_counter() - t0, 0, None)
        out.append(case)
    return out


def configurations(
    inputs: list[MpcInput] | None,
) -> list[tuple[str, Callable[[list[QpProblem]], list[Case]]]]:
    base = QpSettings(
        eps_abs=1e-6, eps_gap_abs=1e-6, max_iter=100, max_iter_in=10, eps_primal_inf=1e-9
    )
    scaled = replace(base, scaling=True, preconditioner=False)
    out: list[tuple[str, Callable[[list[QpProblem]], list[Case]]]] = []
    if inputs is not None:
        out += [
            ("daqp, least-distance form (MPC default)", least_distance_runner(inputs, False)),
            ("daqp, least-distance form, warm", least_distance_runner(inputs, True)),
        ]
    out += [
        ("daqp, its own transformation", qp_solver_runner("daqp", base)),
        (
            "daqp, its own transformation, warm",
            qp_solver_runner("daqp", replace(base, warm_start=True)),
        ),
        ("proxsuite, own preconditioner", qp_solver_runner("proxsuite", base)),
        ("proxsuite, Jacobi scaling", qp_solver_runner("proxsuite", scaled)),
        (
            "proxsuite, Jacobi scaling, warm",
            qp_solver_runner("proxsuite", replace(scaled, warm_start=True)),
        ),
        ("piqp, own preconditioner", qp_solver_runner("piqp", base)),
        ("piqp, Jacobi scaling", qp_solver_runner("piqp", scaled)),
    ]
    if quadprog is not None:
        out.append(("quadprog (cold)", quadprog_runner))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--n", type=int, default=300, help="problems per set")
    args = ap.parse_args()
    if os.environ.get("OMP_NUM_THREADS") != "1":
        print("warning: set OMP_NUM_THREADS=1 for single-core figures")
    sets: dict[str, tuple[list[QpProblem], list[MpcInput] | None]] = {}
    for name, inputs in mpc_inputs(args.n).items():
        mpc = MultiContactMpc()
        sets[f"MPC {name}"] = ([mpc.build_qp(inp) for inp in inputs], inputs)
    sets["WBC-like 38 vars"] = (wbc_like_problems(args.n), None)
    ref_settings = QpSettings(eps_abs=1e-10, eps_gap_abs=1e-10, scaling=True, max_iter=300)
    print(
        f"{'problem':18s} {'configuration':42s} {'median':>7s} {'p99':>7s}  iters  max|dx|  fails"
    )
    for set_name, (problems, inputs) in sets.items():
        p0 = problems[0]
        print(f"-- {set_name}: n {p0.n}, n_eq {p0.n_eq}, n_in {p0.n_in}, box {p0.has_box}")
        refs = [QpSolver("piqp", ref_settings).solve(p).x for p in problems]
        for name, runner in configurations(inputs):
            cases = runner(problems)
            t = np.array([c.time_s for c in cases]) * 1e6
            iters = [c.iterations for c in cases]
            errs = [
                float(np.max(np.abs(c.x - ref)))
                for c, ref in zip(cases, refs, strict=True)
                if c.x is not None
            ]
            fails = sum(c.x is None for c in cases)
            err = max(errs) if errs else math.nan
            print(
                f"{set_name:18s} {name:42s} {np.median(t):7.0f} {np.percentile(t, 99):7.0f}"
                f"  {np.median(iters):3.0f}/{max(iters):3d}  {err:9.1e}  {fails:5d}"
            )


if __name__ == "__main__":
    main()
