"""The lean QP path (locoplan.control.qp.LeanDenseQp, daqp called directly) against the
generic `QpSolver`."""

from __future__ import annotations

import math

import numpy as np
import pytest

from locoplan.control.qp import LeanDenseQp, QpProblem, QpSettings, QpSolver


def _random_qp(
    rng: np.random.Generator, n: int, m: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A strictly convex, feasible QP whose unconstrained minimiser violates some rows: the
    bounds hold at a point x_f, the minimiser lies a random step away from it; about a fifth
    of the rows are one-sided."""
    A = rng.normal(size=(n, n))
    H = A @ A.T + 0.5 * np.eye(n)
    x_f = rng.normal(size=n)
    x_u = x_f + rng.normal(size=n)
    g = -H @ x_u
    C = rng.normal(size=(m, n))
    c = C @ x_f
    l = c - rng.uniform(0.1, 1.5, size=m)
    u = c + rng.uniform(0.1, 1.5, size=m)
    l[rng.random(m) < 0.2] = -math.inf
    u[rng.random(m) < 0.2] = math.inf
    return H, g, C, l, u


def _generic(H, g, C, l, u):  # type: ignore[no-untyped-def]
    """The generic path at a tight tolerance (proxsuite, else piqp where proxsuite stalls)."""
    problem = QpProblem(H=H, g=g, C=C, l=l, u=u)
    settings = QpSettings(eps_abs=1e-10, max_iter=500)
    sol = QpSolver("proxsuite", settings).solve(problem)
    return sol if sol.ok else QpSolver("piqp", settings).solve(problem)


@pytest.mark.parametrize(("n", "m"), [(5, 25), (10, 34), (8, 8), (3, 12)])
def test_lean_equals_generic_on_random_qps(n: int, m: int) -> None:
    rng = np.random.default_rng(n * 100 + m)
    lean = LeanDenseQp(QpSettings(eps_abs=1e-9))
    n_active = 0
    # One solver for the whole sequence: nothing of one solve may leak into the next.
    for _ in range(40):
        H, g, C, l, u = _random_qp(rng, n, m)
        got = lean.solve(H, g, C, l, u)
        want = _generic(H, g, C, l, u)
        assert want.ok
        assert got.ok, got.status
        n_active += int(np.count_nonzero(got.z_in))
        # Both within ~1e-9 of the unique optimum (H positive definite, data O(1)).
        np.testing.assert_allclose(got.x, want.x, rtol=0, atol=1e-6)
        assert got.objective == pytest.approx(want.objective, abs=1e-6)
        # KKT of the lean result: stationarity, sign of the multipliers, complementarity.
        np.testing.assert_allclose(H @ got.x + g + C.T @ got.z_in, 0.0, atol=1e-9)
        Cx = C @ got.x
        assert np.all(Cx >= l - 1e-9) and np.all(Cx <= u + 1e-9)
        up, low = got.z_in > 0, got.z_in < 0
        np.testing.assert_allclose(Cx[up], u[up], atol=1e-9)
        np.testing.assert_allclose(Cx[low], l[low], atol=1e-9)
    assert n_active > 40


def test_unconstrained_minimiser_when_it_is_feasible() -> None:
    rng = np.random.default_rng(1)
    H, g, C, _, _ = _random_qp(rng, 6, 10)
    x_u = -np.linalg.solve(H, g)
    got = LeanDenseQp().solve(H, g, C, C @ x_u - 1.0, C @ x_u + 1.0)
    assert got.ok
    np.testing.assert_allclose(got.x, x_u, atol=1e-12)
    assert not np.any(got.z_in)


def test_the_same_problem_twice_gives_the_same_answer() -> None:
    """reset() and repeated solves: the solver keeps nothing between solves."""
    rng = np.random.default_rng(2)
    H, g, C, l, u = _random_qp(rng, 8, 30)
    lean = LeanDenseQp()
    first = lean.solve(H, g, C, l, u)
    lean.reset()
    second = lean.solve(H, g, C, l, u)
    x, status, iterations = lean.solve_x(H, g, C, l, u)
    assert first.ok and second.ok and status == "solved"
    assert np.count_nonzero(first.z_in) > 0
    assert second.iterations == iterations == first.iterations
    # Bit-identical: the same data through the same deterministic C code.
    np.testing.assert_array_equal(second.x, first.x)
    np.testing.assert_array_equal(x, first.x)


def test_infeasible_problem() -> None:
    H = np.eye(2)
    g = np.zeros(2)
    C = np.array([[1.0, 0.0], [1.0, 0.0]])
    got = LeanDenseQp().solve(H, g, C, np.array([1.0, -math.inf]), np.array([math.inf, 0.0]))
    assert not got.ok and got.status == "primal_infeasible"


def test_not_positive_definite() -> None:
    H = np.diag([1.0, -1.0])
    got = LeanDenseQp().solve(H, np.zeros(2), np.eye(2), -np.ones(2), np.ones(2))
    assert not got.ok and got.status == "numerical_error"


def test_iteration_cap() -> None:
    rng = np.random.default_rng(3)
    H, g, C, l, u = _random_qp(rng, 10, 40)
    assert LeanDenseQp().solve(H, g, C, l, u).iterations > 1
    got = LeanDenseQp(QpSettings(max_iter=1)).solve(H, g, C, l, u)
    assert not got.ok and got.status == "max_iterations"


def test_inverted_bounds_are_infeasible() -> None:
    """l > u on one row (f_min > f_max in the WBC): DAQP does not check it, LeanDenseQp does."""
    rng = np.random.default_rng(4)
    H, g, C, l, u = _random_qp(rng, 5, 25)
    l[3], u[3] = 1.0, 0.5
    for got in (LeanDenseQp().solve(H, g, C, l, u), LeanDenseQp().solve(H, g, C, u, l)):
        assert not got.ok and got.status == "primal_infeasible"


@pytest.mark.parametrize("seed", range(6))
def test_solve_x_takes_a_feasible_unconstrained_minimiser_and_solves_otherwise(seed: int) -> None:
    """With the caller's -H^-1 g: returned as is (0 iterations) when it meets every row;
    otherwise DAQP's solution, the same as without the hint."""
    rng = np.random.default_rng(seed)
    H, g, C, l, u = _random_qp(rng, 6, 20)
    x_u = -np.linalg.solve(H, g)
    lean = LeanDenseQp(QpSettings(eps_abs=1e-9))
    # Violated rows (the generator puts x_u away from the feasible point): DAQP solves.
    got = lean.solve_x(H, g, C, l, u, x_unconstrained=x_u)
    want = lean.solve_x(H, g, C, l, u)
    assert got[1] == "solved" and got[2] > 0
    np.testing.assert_array_equal(got[0], want[0])
    # Bounds widened around C x_u: the minimiser itself, no solver call.
    c = C @ x_u
    x, status, iterations = lean.solve_x(H, g, C, c - 1.0, c + 1.0, x_unconstrained=x_u)
    assert (status, iterations) == ("solved", 0)
    assert x is x_u
    # DAQP would return the same point to rounding.
    ref = lean.solve_x(H, g, C, c - 1.0, c + 1.0)
    np.testing.assert_allclose(ref[0], x_u, rtol=0, atol=1e-9)
