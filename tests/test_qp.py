"""Tests of locoplan.control.qp against problems with known optima, on every backend
(proxsuite, piqp, daqp), and of daqp's least-distance path.

Tolerances: the solvers run at eps_abs = 1e-9 on these well-conditioned problems (condition
numbers below 1e3), so 1e-6 on x leaves three orders of margin for the solvers' regularisation
and for the difference between interior-point (piqp), augmented-Lagrangian (proxsuite) and
active-set (daqp, exact up to rounding) end points.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse as sp

from locoplan.control.qp import (
    BACKENDS,
    LeastDistanceForm,
    QpProblem,
    QpSettings,
    QpSolver,
    active_constraint_ids,
    constraint_id,
    solve_qp,
)

TIGHT = QpSettings(eps_abs=1e-9, eps_gap_abs=1e-9)
TOL = 1e-6  # see the module docstring


def _kkt_equality_ls(D: np.ndarray, e: np.ndarray, A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Closed form of min 1/2 |D x - e|^2 s.t. A x = b through the KKT system."""
    n, m = D.shape[1], A.shape[0]
    K = np.block([[D.T @ D, A.T], [A, np.zeros((m, m))]])
    rhs = np.concatenate([D.T @ e, b])
    return np.linalg.solve(K, rhs)[:n]


def _stationarity(p: QpProblem, sol) -> np.ndarray:  # type: ignore[no-untyped-def]
    r = p.H @ sol.x + p.g + sol.z_box
    if p.A is not None:
        r = r + p.A.T @ sol.y_eq
    if p.C is not None:
        r = r + p.C.T @ sol.z_in
    return np.asarray(r)


@pytest.mark.parametrize("backend", BACKENDS)
def test_equality_constrained_least_squares(backend: str) -> None:
    rng = np.random.default_rng(0)
    D = rng.normal(size=(8, 5))
    e = rng.normal(size=8)
    A = rng.normal(size=(2, 5))
    b = rng.normal(size=2)
    p = QpProblem(H=D.T @ D, g=-D.T @ e, A=A, b=b)
    sol = solve_qp(p, backend, TIGHT)
    assert sol.ok and sol.status == "solved"
    np.testing.assert_allclose(sol.x, _kkt_equality_ls(D, e, A, b), atol=TOL)
    np.testing.assert_allclose(A @ sol.x, b, atol=TOL)
    # Duals in the documented convention: H x + g + A'y = 0 (1e-6: dual residual tolerance).
    np.testing.assert_allclose(_stationarity(p, sol), 0.0, atol=TOL)
    assert math.isclose(sol.objective, p.objective(sol.x))


@pytest.mark.parametrize("backend", BACKENDS)
def test_active_box(backend: str) -> None:
    # min 1/2 |x - c|^2 on a box: the optimum is the clipped c; two bounds active, one side
    # of the box infinite.
    c = np.array([2.0, -3.0, 0.5, 0.1])
    lo = np.array([-1.0, -1.0, -np.inf, -1.0])
    hi = np.array([1.0, np.inf, 1.0, 1.0])
    p = QpProblem(H=np.eye(4), g=-c, x_lower=lo, x_upper=hi)
    sol = solve_qp(p, backend, TIGHT)
    assert sol.ok
    np.testing.assert_allclose(sol.x, np.clip(c, lo, hi), atol=TOL)
    # Box multipliers: +1 on the active upper bound (x0), -2 on the active lower (x1).
    np.testing.assert_allclose(sol.z_box, [1.0, -2.0, 0.0, 0.0], atol=TOL)
    np.testing.assert_allclose(_stationarity(p, sol), 0.0, atol=TOL)


@pytest.mark.parametrize("backend", BACKENDS)
def test_active_inequality(backend: str) -> None:
    # Projection of c onto the half-space a'x <= beta, written two-sided with l = -inf, plus
    # an inactive second row with both sides finite.
    c = np.array([1.0, 2.0, 3.0])
    a = np.array([1.0, 1.0, 1.0])
    beta = 2.0
    C = np.vstack([a, [1.0, -1.0, 0.0]])
    p = QpProblem(H=np.eye(3), g=-c, C=C, l=np.array([-np.inf, -5.0]), u=np.array([beta, 5.0]))
    expected = c - (a @ c - beta) / (a @ a) * a
    sol = solve_qp(p, backend, TIGHT)
    assert sol.ok
    np.testing.assert_allclose(sol.x, expected, atol=TOL)
    np.testing.assert_allclose(sol.z_in, [(a @ c - beta) / (a @ a), 0.0], atol=TOL)
    np.testing.assert_allclose(_stationarity(p, sol), 0.0, atol=TOL)


@pytest.mark.parametrize("backend", BACKENDS)
def test_infeasible_is_not_ok(backend: str) -> None:
    # x0 + x1 = 1 with 0 <= x <= 0.4 has no solution.
    p = QpProblem(
        H=np.eye(2),
        g=np.zeros(2),
        A=np.ones((1, 2)),
        b=np.array([1.0]),
        x_lower=np.zeros(2),
        x_upper=np.full(2, 0.4),
    )
    sol = solve_qp(p, backend, QpSettings(max_iter=200))
    assert not sol.ok
    assert sol.status in {"primal_infeasible", "max_iterations", "closest_primal_feasible"}


@pytest.mark.parametrize("backend", BACKENDS)
def test_iteration_cap_is_not_ok(backend: str) -> None:
    rng = np.random.default_rng(1)
    M = rng.normal(size=(20, 20))
    p = QpProblem(
        H=M @ M.T + np.eye(20),
        g=rng.normal(size=20),
        C=rng.normal(size=(15, 20)),
        l=-np.ones(15),
        u=np.ones(15) * 0.1,
    )
    sol = solve_qp(p, backend, QpSettings(max_iter=1))
    assert not sol.ok and sol.status == "max_iterations"


def _random_problem(seed: int, sparse: bool = False) -> QpProblem:
    """A whole-body-QP-like problem: 38 variables, 6 equalities, 30 inequalities, a box."""
    rng = np.random.default_rng(seed)
    n = 38
    M = rng.normal(size=(n, n))
    H = M @ M.T / n + 0.1 * np.eye(n)
    g = rng.normal(size=n)
    A = rng.normal(size=(6, n))
    b = rng.normal(size=6) * 0.1
    C = rng.normal(size=(30, n))
    l = np.full(30, -0.5)
    l[::3] = -np.inf
    u = np.full(30, 0.5)
    lo = np.full(n, -1.0)
    hi = np.full(n, 1.0)
    hi[::4] = np.inf
    if sparse:
        return QpProblem(
            H=sp.csc_matrix(H),
            g=g,
            A=sp.csc_matrix(A),
            b=b,
            C=sp.csc_matrix(C),
            l=l,
            u=u,
            x_lower=lo,
            x_upper=hi,
        )
    return QpProblem(H=H, g=g, A=A, b=b, C=C, l=l, u=u, x_lower=lo, x_upper=hi)


def test_backends_agree_dense_and_sparse() -> None:
    for seed in range(5):
        sols = [
            solve_qp(_random_problem(seed, sparse), b, TIGHT)
            for b in BACKENDS
            for sparse in (False, True)
        ]
        for s in sols:
            assert s.ok, s.status
            np.testing.assert_allclose(s.x, sols[0].x, atol=TOL)
            assert math.isclose(s.objective, sols[0].objective, rel_tol=1e-7, abs_tol=1e-7)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("warm_start", [False, True])
def test_reuse_matches_fresh_solver(backend: str, warm_start: bool) -> None:
    solver = QpSolver(backend, QpSettings(eps_abs=1e-9, eps_gap_abs=1e-9, warm_start=warm_start))
    for seed in range(4):
        p = _random_problem(seed)
        s = solver.solve(p)
        fresh = solve_qp(p, backend, TIGHT)
        assert s.ok and fresh.ok
        # daqp keeps no solver object (one-shot daqp.solve), only the previous active set.
        assert s.reused == (seed > 0 and backend != "daqp")
        np.testing.assert_allclose(s.x, fresh.x, atol=TOL)
        assert s.solve_time_s >= s.setup_time_s >= 0.0


@pytest.mark.parametrize("backend", BACKENDS)
def test_dimension_change_rebuilds(backend: str) -> None:
    solver = QpSolver(backend, TIGHT)
    s1 = solver.solve(QpProblem(H=np.eye(2), g=-np.ones(2)))
    s2 = solver.solve(QpProblem(H=np.eye(3), g=-np.ones(3), x_upper=np.full(3, 0.5)))
    assert s1.ok and s2.ok and not s2.reused
    np.testing.assert_allclose(s2.x, 0.5, atol=TOL)


def test_bad_arguments_rejected() -> None:
    with pytest.raises(ValueError):
        QpProblem(H=np.eye(3), g=np.zeros(2))
    with pytest.raises(ValueError):
        QpProblem(H=np.eye(2), g=np.zeros(2), A=np.ones((1, 2)))
    with pytest.raises(ValueError):
        QpProblem(H=np.eye(2), g=np.zeros(2), C=np.ones((1, 2)))
    with pytest.raises(ValueError):
        QpProblem(H=np.eye(2), g=np.zeros(2), x_lower=np.zeros(3))
    with pytest.raises(ValueError):
        QpSolver("osqp")
    with pytest.raises(ValueError):
        QpSettings(max_iter=0)


def test_warm_start_never_reports_a_wrong_optimum() -> None:
    # proxsuite 0.8 warm-started after update() returned feasible, non-optimal points as
    # solved on such consecutive problems; the complementarity check must flag them.
    rng = np.random.default_rng(0)
    n = 38
    M = rng.normal(size=(n, n))
    H0 = M @ M.T / n + 0.1 * np.eye(n)
    A0, C0 = rng.normal(size=(6, n)), rng.normal(size=(30, n))
    solver = QpSolver(
        "proxsuite",
        QpSettings(
            eps_abs=1e-6, eps_gap_abs=1e-6, warm_start=True, scaling=True, preconditioner=False
        ),
    )
    n_ok = 0
    for _ in range(30):
        dH = rng.normal(scale=0.01, size=(n, n))
        p = QpProblem(
            H=H0 + dH @ dH.T,
            g=rng.normal(size=n),
            A=A0 + rng.normal(scale=0.01, size=A0.shape),
            b=rng.normal(scale=0.2, size=6),
            C=C0 + rng.normal(scale=0.01, size=C0.shape),
            l=np.full(30, -1.0),
            u=np.full(30, 1.0),
            x_lower=np.full(n, -2.0),
            x_upper=np.full(n, 2.0),
        )
        sol = solver.solve(p)
        if sol.ok:
            n_ok += 1
            ref = solve_qp(p, "piqp", TIGHT)
            # 1e-4: the warm solve runs at eps 1e-6 on a problem with multipliers O(1-10).
            np.testing.assert_allclose(sol.x, ref.x, atol=1e-4)
        else:
            assert sol.status in {"inaccurate", "max_iterations"}
    assert n_ok > 0


def _least_distance(p: QpProblem) -> LeastDistanceForm:
    """x_u = -H^-1 g, U = L^-T (H = L L') and W = [U[box]; C U], the form's definition,
    computed plainly."""
    U = np.linalg.inv(np.linalg.cholesky(p.H)).T
    lo = p.x_lower if p.x_lower is not None else np.full(p.n, -np.inf)
    hi = p.x_upper if p.x_upper is not None else np.full(p.n, np.inf)
    box = np.flatnonzero(np.isfinite(lo) | np.isfinite(hi))
    W = np.vstack([U[box], p.C @ U])
    return LeastDistanceForm.from_dense(-np.linalg.solve(p.H, p.g), U, W)


def _inequality_problem(seed: int, scale: float = 1.0) -> QpProblem:
    """_random_problem without its equalities; ``scale`` < 1 shrinks g (fewer active bounds)."""
    p = _random_problem(seed)
    return QpProblem(
        H=p.H, g=scale * p.g, C=p.C, l=p.l, u=p.u, x_lower=p.x_lower, x_upper=p.x_upper
    )


def test_daqp_least_distance_matches_piqp() -> None:
    rounds = []
    for seed in range(4):
        p = _inequality_problem(seed)
        form = _least_distance(p)
        asked: list[np.ndarray] = []

        def rows(
            idx: np.ndarray, form: LeastDistanceForm = form, asked: list[np.ndarray] = asked
        ) -> np.ndarray:
            asked.append(np.array(idx))
            return form.rows(idx)

        sol = QpSolver("daqp", TIGHT).solve(p, least_distance=replace(form, rows=rows))
        ref = solve_qp(p, "piqp", TIGHT)
        # DAQP sees a subset of W's rows, growing by the rows its optimum violates; each
        # round's rows hold the previous round's.
        rounds.append(len(asked))
        assert asked[0].shape[0] < p.n + p.n_in
        for a, b in itertools.pairwise(asked):
            assert np.isin(a, b).all() and b.shape[0] > a.shape[0]
        assert sol.ok and ref.ok and sol.iterations > 0
        np.testing.assert_allclose(sol.x, ref.x, atol=TOL)
        # Multipliers of W's rows are the QP's: stationarity in x to 1e-6 (TOL).
        np.testing.assert_allclose(_stationarity(p, sol), 0.0, atol=TOL)
        np.testing.assert_allclose(sol.z_in, ref.z_in, atol=TOL)
        np.testing.assert_allclose(sol.z_box, ref.z_box, atol=TOL)
    # These problems take more than one round (measured: 2-3 rounds each).
    assert max(rounds) > 1


def test_daqp_least_distance_unconstrained_minimiser() -> None:
    # g scaled down so far that -H^-1 g meets every bound: no DAQP iteration at all.
    p = _inequality_problem(0, scale=1e-3)
    form = _least_distance(p)

    def no_factor(*_: object) -> np.ndarray:
        raise AssertionError("U and W are not needed when x_u meets every bound")

    sol = QpSolver("daqp", TIGHT).solve(
        p, least_distance=replace(form, factor=no_factor, rows=no_factor)
    )
    assert sol.ok and sol.iterations == 0
    np.testing.assert_allclose(sol.x, -np.linalg.solve(p.H, p.g), atol=1e-12)
    assert not np.any(sol.z_in) and not np.any(sol.z_box)


def test_daqp_active_hint_changes_iterations_not_the_optimum() -> None:
    p = _inequality_problem(1)
    form = _least_distance(p)
    warm = replace(TIGHT, warm_start=True)
    cold = QpSolver("daqp", TIGHT).solve(p, least_distance=form)
    # The optimum's own active set: DAQP starts at the optimum.
    good = QpSolver("daqp", warm).solve(
        p, active_hint=active_constraint_ids(cold), least_distance=form
    )
    # A wrong guess: every upper bound of C's rows (more rows than variables).
    bad_ids = constraint_id(p.n_in, p.n, np.arange(p.n_in), np.ones(p.n_in, dtype=bool))
    bad = QpSolver("daqp", warm).solve(p, active_hint=bad_ids, least_distance=form)
    for s in (good, bad):
        assert s.ok, s.status
        np.testing.assert_allclose(s.x, cold.x, atol=TOL)
    assert good.iterations < cold.iterations
    # The plain path takes the hint too.
    plain = QpSolver("daqp", warm).solve(p, active_hint=active_constraint_ids(cold))
    assert plain.ok and plain.iterations < cold.iterations
    np.testing.assert_allclose(plain.x, cold.x, atol=TOL)


def test_daqp_least_distance_infeasible_is_not_ok() -> None:
    # A box lower bound above the upper bound, and an empty intersection of rows.
    p = _inequality_problem(2)
    lo = np.array(p.x_lower, copy=True)
    lo[1] = 2.0  # x_upper[1] = 1
    bad_box = replace(p, x_lower=lo)
    C = np.vstack([np.ones(p.n), -np.ones(p.n)])
    bad_rows = QpProblem(H=p.H, g=p.g, C=C, l=np.array([1.0, 1.0]), u=np.array([np.inf] * 2))
    solver = QpSolver("daqp", TIGHT)
    for q in (bad_box, bad_rows, bad_box):
        sol = solver.solve(q, least_distance=_least_distance(q))
        assert not sol.ok and sol.status == "primal_infeasible"
    # The solver recovers on a feasible problem afterwards.
    assert solver.solve(p, least_distance=_least_distance(p)).ok


@pytest.mark.parametrize("where", ["row", "box"])
def test_daqp_inverted_bounds_are_infeasible(where: str) -> None:
    """DAQP does not check l <= u itself (it reported "solved" 50 N off the bounds on the WBC
    QP with f_min > f_max); QpSolver must, on both of its daqp paths."""
    p = _inequality_problem(2)
    if where == "row":
        l, u = np.array(p.l, copy=True), np.array(p.u, copy=True)
        l[0], u[0] = 1.0, 0.5
        bad = replace(p, l=l, u=u)
    else:
        lo, hi = np.array(p.x_lower, copy=True), np.array(p.x_upper, copy=True)
        lo[0], hi[0] = 1.0, 0.5
        bad = replace(p, x_lower=lo, x_upper=hi)
    assert not QpSolver("daqp", TIGHT).solve(bad).ok
    sol = QpSolver("daqp", TIGHT).solve(bad, least_distance=_least_distance(bad))
    assert not sol.ok and sol.status == "primal_infeasible"
