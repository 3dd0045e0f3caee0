"""Tests of the dual active-set method (locoplan.control.qp_active_set) against closed forms and
against piqp. QpSolver no longer uses it (the MPC solves with daqp); it stays while
qp.LeanDenseQp (the WBC's lean path) falls back to it.

Tolerances: the method is exact up to rounding once it stops (stationarity holds by
construction, the bounds to ``tol``); on these problems (cond(H) < 1e4) 1e-8 on x is
rounding plus the reference solver's own 1e-10 accuracy.
"""

from __future__ import annotations

import numpy as np
import pytest

from locoplan.control.qp import QpProblem, QpSettings, solve_qp
from locoplan.control.qp_active_set import constraint_ids, solve_dual_active_set

TOL = 1e-8


def _random(seed: int, n: int = 30, m: int = 40) -> QpProblem:
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(n, n))
    H = M @ M.T / n + 0.05 * np.eye(n)
    C = rng.normal(size=(m, n))
    l = np.full(m, -0.3)
    l[::4] = -np.inf
    u = np.full(m, 0.4)
    u[1::5] = np.inf
    lo = np.full(n, -0.5)
    hi = np.full(n, 0.5)
    lo[::3] = -np.inf
    return QpProblem(H=H, g=3.0 * rng.normal(size=n), C=C, l=l, u=u, x_lower=lo, x_upper=hi)


def test_unconstrained_minimiser_when_nothing_is_active() -> None:
    H = np.diag([2.0, 4.0])
    r = solve_dual_active_set(H, np.array([-2.0, -4.0]), x_upper=np.array([5.0, 5.0]))
    assert r.status == "solved" and r.iterations == 0 and r.n_active == 0
    np.testing.assert_allclose(r.x, [1.0, 1.0], atol=1e-15)


def test_projection_onto_half_space_and_box() -> None:
    c = np.array([1.0, 2.0, 3.0])
    a = np.ones(3)
    r = solve_dual_active_set(np.eye(3), -c, C=a[None, :], u=np.array([2.0]))
    expected = c - (a @ c - 2.0) / 3.0 * a
    np.testing.assert_allclose(r.x, expected, atol=1e-14)
    np.testing.assert_allclose(r.z_in, [(a @ c - 2.0) / 3.0], atol=1e-14)
    r = solve_dual_active_set(
        np.eye(2), -np.array([2.0, -3.0]), x_lower=-np.ones(2), x_upper=np.ones(2)
    )
    np.testing.assert_allclose(r.x, [1.0, -1.0], atol=1e-15)
    np.testing.assert_allclose(r.z_box, [1.0, -2.0], atol=1e-15)


def test_dependent_constraints_and_drops() -> None:
    # Three copies of the same constraint and one implied by two others: the method must
    # not add linearly dependent normals (its S matrix would be singular).
    H = np.eye(2)
    g = -np.array([3.0, 3.0])
    C = np.array([[1.0, 1.0], [1.0, 1.0], [2.0, 2.0], [1.0, 0.0], [0.0, 1.0]])
    u = np.array([1.0, 1.0, 2.0, 0.5, 0.5])
    r = solve_dual_active_set(H, g, C=C, u=u)
    assert r.status == "solved"
    np.testing.assert_allclose(r.x, [0.5, 0.5], atol=1e-14)
    np.testing.assert_allclose(H @ r.x + g + C.T @ r.z_in, 0.0, atol=1e-13)


def test_infeasible_is_certified() -> None:
    # x0 + x1 >= 1 with both <= 0.4.
    r = solve_dual_active_set(
        np.eye(2), np.zeros(2), C=np.ones((1, 2)), l=np.array([1.0]), x_upper=np.full(2, 0.4)
    )
    assert r.status == "infeasible"


def test_not_positive_definite() -> None:
    r = solve_dual_active_set(np.diag([1.0, 0.0]), np.zeros(2))
    assert r.status == "not_positive_definite"


@pytest.mark.parametrize("seed", range(8))
def test_matches_piqp_on_random_problems(seed: int) -> None:
    p = _random(seed)
    ref = solve_qp(p, "piqp", QpSettings(eps_abs=1e-11, eps_gap_abs=1e-11))
    r = solve_dual_active_set(
        p.H, p.g, p.C, p.l, p.u, p.x_lower, p.x_upper, tol=1e-12, max_iter=200
    )
    assert ref.ok and r.status == "solved"
    assert r.n_active > 0
    np.testing.assert_allclose(r.x, ref.x, atol=TOL)
    # KKT: stationarity, multiplier signs, complementarity. x and the multipliers are
    # updated incrementally over up to ~100 iterations (S^-1 by bordering and downdating), so
    # rounding accumulates to ~1e-10 on these O(1)-O(10) quantities; 1e-8 bounds it.
    assert p.C is not None
    np.testing.assert_allclose(p.H @ r.x + p.g + p.C.T @ r.z_in + r.z_box, 0.0, atol=1e-8)
    Cx = p.C @ r.x
    assert np.all(r.z_in[r.z_in > 0] >= 0) and np.all(
        np.isclose(Cx[r.z_in > 1e-12], p.u[r.z_in > 1e-12])
    )
    assert np.all(np.isclose(Cx[r.z_in < -1e-12], p.l[r.z_in < -1e-12]))


def test_iteration_cap_reported() -> None:
    p = _random(0)
    r = solve_dual_active_set(p.H, p.g, p.C, p.l, p.u, p.x_lower, p.x_upper, max_iter=1)
    assert r.status == "max_iterations"


@pytest.mark.parametrize("seed", range(4))
def test_initial_active_guess_gives_the_same_optimum(seed: int) -> None:
    p = _random(seed)
    args = (p.H, p.g, p.C, p.l, p.u, p.x_lower, p.x_upper, 1e-12, 300)
    cold = solve_dual_active_set(*args)
    z = np.concatenate([cold.z_in, cold.z_box])
    nz = np.flatnonzero(z)
    exact = constraint_ids(p.n_in, p.n, nz, z[nz] > 0)
    warm = solve_dual_active_set(*args, initial_active=exact)
    assert warm.status == "solved" and warm.iterations == 0
    rng = np.random.default_rng(seed)
    junk = rng.integers(0, 2 * (p.n_in + p.n), size=20)  # arbitrary, partly contradictory
    for guess in (exact[::2], junk, np.zeros(0, dtype=np.intp)):
        r = solve_dual_active_set(*args, initial_active=guess)
        assert r.status == "solved"
        # Same optimum from any dual-feasible start: rounding only (see the KKT test).
        np.testing.assert_allclose(r.x, cold.x, atol=1e-8)
