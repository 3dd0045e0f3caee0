"""piqp vs proxsuite (and the dual active-set path) on the MPC QP and on a WBC-like dense QP.

Run: OMP_NUM_THREADS=1 .venv/bin/python benchmarks/qp_backends.py [--n 300]

1. The MPC QP (horizon 20, condensed, foot-frame wrenches): the problems met in the closed
   loops of benchmarks/mpc_qp.py (standing and stepping, state noise level 1), solved in
   order by one QpSolver per configuration, so re-use of the solver object counts.
2. A dense QP like the whole-body QP: 38 variables, random SPD H, 6 equalities, 30
   two-sided inequalities, a box; consecutive problems differ by a small random change, as
   ticks of a control loop do.

Times in microseconds (wall time of QpSolver.solve: scaling, setup/update and solve),
median / p99, and the largest difference from a piqp reference at eps 1e-10.
"""

from __future__ import annotations

import argparse
import os
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from locoplan.control.mpc import MpcSettings, MultiContactMpc
from locoplan.control.qp import QpProblem, QpSettings, QpSolver

sys.path.insert(0, str(Path(__file__).resolve().parent))
import mpc_qp


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


def mpc_problems(count: int) -> dict[str, list[QpProblem]]:
    """The condensed MPC QPs met in the benchmark closed loops."""
    out = {}
    for name, schedule in (
        ("standing", mpc_qp.standing_contact),
        ("stepping", mpc_qp.stepping_contact),
    ):
        mpc = MultiContactMpc(MpcSettings())
        inputs = mpc_qp.record_inputs(schedule, count)
        out[name] = [mpc.build_qp(inp) for inp in inputs]
    return out


def configurations(mpc: bool) -> list[tuple[str, str, QpSettings]]:
    base = QpSettings(
        eps_abs=1e-6, eps_gap_abs=1e-6, max_iter=50, max_iter_in=10, eps_primal_inf=1e-9
    )
    scaled = replace(base, scaling=True, preconditioner=False)
    out = [
        ("proxsuite, own preconditioner", "proxsuite", base),
        ("proxsuite, Jacobi scaling", "proxsuite", scaled),
        ("proxsuite, Jacobi scaling, warm", "proxsuite", replace(scaled, warm_start=True)),
        ("piqp, own preconditioner", "piqp", base),
        ("piqp, Jacobi scaling", "piqp", scaled),
    ]
    if mpc:
        out.insert(
            0,
            (
                "active set, then proxsuite (MPC default)",
                "proxsuite",
                replace(scaled, active_set_iter=50),
            ),
        )
    return out


def run(problems: list[QpProblem], backend: str, settings: QpSettings) -> dict[str, float]:
    ref_settings = QpSettings(eps_abs=1e-10, eps_gap_abs=1e-10, scaling=True, max_iter=300)
    refs = [QpSolver("piqp", ref_settings).solve(p).x for p in problems]
    solver = QpSolver(backend, settings)
    solver.solve(problems[0])
    times, iters, err = [], [], 0.0
    fails = 0
    for p, ref in zip(problems, refs, strict=True):
        sol = solver.solve(p)
        times.append(sol.solve_time_s * 1e6)
        iters.append(sol.iterations)
        if sol.ok:
            err = max(err, float(np.max(np.abs(sol.x - ref))))
        else:
            fails += 1
    t = np.array(times)
    return {
        "median": float(np.median(t)),
        "p99": float(np.percentile(t, 99)),
        "iters": float(np.median(iters)),
        "max_iters": float(np.max(iters)),
        "err": err,
        "fails": fails,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--n", type=int, default=300, help="problems per set")
    args = ap.parse_args()
    if os.environ.get("OMP_NUM_THREADS") != "1":
        print("warning: set OMP_NUM_THREADS=1 for single-core figures")
    sets: dict[str, tuple[list[QpProblem], bool]] = {
        f"MPC {k}": (v, True) for k, v in mpc_problems(args.n).items()
    }
    sets["WBC-like 38 vars"] = (wbc_like_problems(args.n), False)
    print(
        f"{'problem':18s} {'configuration':42s} {'median':>7s} {'p99':>7s}  iters  max|dx|  fails"
    )
    for set_name, (problems, is_mpc) in sets.items():
        p0 = problems[0]
        print(f"-- {set_name}: n {p0.n}, n_eq {p0.n_eq}, n_in {p0.n_in}, box {p0.has_box}")
        for name, backend, settings in configurations(is_mpc):
            r = run(problems, backend, settings)
            print(
                f"{set_name:18s} {name:42s} {r['median']:7.0f} {r['p99']:7.0f}"
                f"  {r['iters']:3.0f}/{r['max_iters']:3.0f}  {r['err']:9.1e}  {r['fails']:5d}"
            )


if __name__ == "__main__":
    main()
