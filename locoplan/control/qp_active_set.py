"""Dense dual active-set QP method (Goldfarb & Idnani 1983), numpy only.

Solves ``min 1/2 x'Hx + g'x`` s.t. ``l <= C x <= u`` and ``x_lower <= x <= x_upper`` for a
positive definite H. It starts at the unconstrained minimiser -H^-1 g (one Cholesky
factorisation) and adds the most violated constraint one at a time, dropping constraints
whose multiplier would turn negative; every iterate is dual feasible, and the method stops
when the primal iterate meets every bound to ``tol``: that point satisfies the KKT conditions
(stationarity by construction, multipliers >= 0, complementarity, primal feasibility to tol).
One iteration costs one triangular solve pair with H's factor (O(n^2)) plus O(n m) with m
active constraints, so a problem whose optimum has few active constraints -- the usual MPC
case -- costs little more than the factorisation, unlike interior-point or augmented
Lagrangian methods that refactorise at every iteration.

Internally the constraints are one-sided, n_i' x >= b_i: a lower bound l_j gives
(C_j, l_j), an upper bound u_j gives (-C_j, -u_j), likewise for the box. With the active set
A, V = H^-1 N_A and S = N_A' V, adding constraint p moves the primal iterate along
z = H^-1 n_p - V S^-1 V' n_p (which keeps the active constraints exact) and the active
multipliers along -r, r = S^-1 V' n_p.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import scipy.linalg

FloatArray = npt.NDArray[np.float64]

_potrf, _potrs = scipy.linalg.get_lapack_funcs(("potrf", "potrs"), dtype=np.float64)
_trsv = scipy.linalg.get_blas_funcs("trsv", dtype=np.float64)
_trsm = scipy.linalg.get_blas_funcs("trsm", dtype=np.float64)


def _chol_solve(L: FloatArray, b: FloatArray) -> FloatArray:
    """H^-1 b from the lower Cholesky factor L (H = L L'), two BLAS triangular solves (faster
    than LAPACK potrs for one right-hand side at this size)."""
    return np.asarray(_trsv(L, _trsv(L, b, lower=1, trans=0), lower=1, trans=1))


@dataclass(frozen=True, slots=True)
class ActiveSetResult:
    """Outcome of `solve_dual_active_set`.

    ``status``: "solved", "max_iterations", "infeasible" or "not_positive_definite". ``x``
    (n,) the last iterate. ``iterations``: constraints added plus dropped. ``z_in`` (m_in,)
    and ``z_box`` (n,) multipliers with H x + g + C' z_in + z_box = 0 (positive on an active
    upper bound, negative on an active lower bound). ``max_violation`` of the bounds at x.
    """

    status: str
    x: FloatArray
    iterations: int
    n_active: int
    z_in: FloatArray
    z_box: FloatArray
    max_violation: float


def constraint_ids(
    m: int, n: int, row: npt.ArrayLike, upper: npt.ArrayLike
) -> npt.NDArray[np.intp]:
    """Ids of one-sided constraints: ``row`` < m is a row of C, m + i the box on x_i;
    ``upper`` selects the upper bound (else the lower)."""
    r = np.asarray(row, dtype=np.intp)
    return np.where(np.asarray(upper, dtype=bool), (m + n) + r, r)


def _start_from_guess(
    factor: FloatArray,
    x_u: FloatArray,
    C: FloatArray | None,
    m: int,
    n: int,
    lo: FloatArray,
    hi: FloatArray,
    ids: npt.ArrayLike,
) -> tuple[list[int], FloatArray, FloatArray, FloatArray, FloatArray] | None:
    """Active set, multipliers, W = L^-1 N_A, S = W'W and x for a guessed active set (see
    `solve_dual_active_set`), or None if nothing of the guess is usable."""
    mn = m + n
    cand = np.unique(np.asarray(ids, dtype=np.intp))
    cand = cand[(cand >= 0) & (cand < 2 * mn)]
    row = np.where(cand < mn, cand, cand - mn)
    upper = cand >= mn
    bound = np.where(upper, -hi[row], lo[row])
    ok = np.isfinite(bound)
    # A row cannot be active at both bounds.
    cand, row, upper, bound = cand[ok], row[ok], upper[ok], bound[ok]
    _, first = np.unique(row, return_index=True)
    cand, row, upper, bound = cand[first], row[first], upper[first], bound[first]
    if cand.shape[0] == 0:
        return None
    N_A = np.zeros((n, cand.shape[0]))
    in_c = row < m
    if C is not None and np.any(in_c):
        N_A[:, in_c] = C[row[in_c]].T
    box = np.flatnonzero(~in_c)
    N_A[row[box] - m, box] = 1.0
    N_A[:, upper] *= -1.0
    W_all = np.asarray(_trsm(1.0, factor, N_A, lower=1, trans_a=0))
    S_all = W_all.T @ W_all
    keep = np.ones(cand.shape[0], dtype=bool)
    rhs_all = bound - N_A.T @ x_u
    for _ in range(cand.shape[0]):
        S = S_all[np.ix_(keep, keep)]
        # S = N' H^-1 N is positive definite iff the kept normals are independent; LAPACK
        # directly (scipy.linalg.solve's checks cost ~100 us here).
        S_factor, info = _potrf(S, lower=1, clean=0, overwrite_a=0)
        if info != 0:
            return None
        lam = _potrs(S_factor, rhs_all[keep], lower=1)[0]
        if np.all(lam >= 0.0):
            break
        idx = np.flatnonzero(keep)
        keep[idx[lam < 0.0]] = False
        if not keep.any():
            return None
    else:
        return None
    W = W_all[:, keep]
    x = x_u + np.asarray(_trsv(factor, W @ lam, lower=1, trans=1))
    return [int(i) for i in cand[keep]], lam, W, S, x


def solve_dual_active_set(
    H: FloatArray,
    g: FloatArray,
    C: FloatArray | None = None,
    l: FloatArray | None = None,
    u: FloatArray | None = None,
    x_lower: FloatArray | None = None,
    x_upper: FloatArray | None = None,
    tol: float = 1e-9,
    max_iter: int = 50,
    initial_active: npt.ArrayLike | None = None,
    cholesky: FloatArray | None = None,
) -> ActiveSetResult:
    """Solve the QP by the dual active-set method; see the module docstring.

    H (n, n) positive definite, g (n,), C (m, n) with l/u (m,), box x_lower/x_upper (n,);
    +-inf or None for absent bounds. ``tol`` is the accepted bound violation, ``max_iter``
    caps the iterations (the result is then "max_iterations" and x is not optimal).

    ``initial_active``: a guess of the active set (constraint ids, see `constraint_ids`), e.g.
    the previous solution's in a control loop. The method then starts from the minimiser with
    those constraints as equalities, solved at once with BLAS-3 operations, after dropping
    those with negative multipliers; that start is a valid dual-feasible point, so the result
    is the same optimum, reached in fewer iterations when the guess is good. A guess whose
    normals are linearly dependent is ignored.

    ``cholesky``: the lower Cholesky factor L of H (H = L L', column-major, only the lower
    triangle is read) if the caller has it, e.g. assembled from cached blocks; it replaces
    the factorisation, the method's largest fixed cost.
    """
    n = g.shape[0]
    m = 0 if C is None else C.shape[0]
    # Rows j < m are C's, rows m + i the box on x_i; one-sided constraint id j is the lower
    # bound of row j, id (m + n) + j its upper bound.
    mn = m + n
    lo = np.full(mn, -np.inf)
    hi = np.full(mn, np.inf)
    if l is not None:
        lo[:m] = l
    if u is not None:
        hi[:m] = u
    if x_lower is not None:
        lo[m:] = x_lower
    if x_upper is not None:
        hi[m:] = x_upper
    # H is symmetric: its transpose is a column-major view, which LAPACK takes without a copy
    # (the lower factorisation is also the faster one in OpenBLAS here: 124 vs 166 us, n 200).
    if cholesky is not None:
        factor, info = cholesky, 0
    else:
        factor, info = _potrf(np.asarray(H).T, lower=1, clean=0, overwrite_a=0)
    if info != 0:
        nan = np.full(n, np.nan)
        return ActiveSetResult("not_positive_definite", nan, 0, 0, np.zeros(m), np.zeros(n), np.inf)
    x = -_chol_solve(factor, g)
    rows = np.empty(mn)

    def slacks(x: FloatArray) -> FloatArray:
        if C is not None:
            rows[:m] = C @ x
        rows[m:] = x
        return np.concatenate((rows - lo, hi - rows))

    def normal(i: int) -> FloatArray:
        j = i if i < mn else i - mn
        if j < m:
            assert C is not None
            n_j = C[j]
        else:
            n_j = np.zeros(n)
            n_j[j - m] = 1.0
        return n_j if i < mn else -n_j

    active: list[int] = []
    # Buffers: rows of VT are the columns of V = H^-1 N_A; Sinv = (N_A' H^-1 N_A)^-1 is
    # kept by bordering (add) and its inverse formula (drop); q active constraints in use.
    # Small buffers, doubled when full (at most n independent constraints are active);
    # large ones would cost page faults on every call.
    q = 0
    guess = None
    if initial_active is not None:
        guess = _start_from_guess(factor, x, C, m, n, lo, hi, initial_active)
    cap = min(n, max(16, 2 * len(guess[0]) if guess is not None else 0))
    VT = np.empty((cap, n))
    Sinv = np.empty((cap, cap))
    lam = np.empty(cap)
    pending: tuple[FloatArray, FloatArray] | None = None
    if guess is not None:
        active, lam0, W0, S0, x = guess
        q = len(active)
        lam[:q] = lam0
        # V = L^-T W and S^-1 only when an iteration needs them: a good guess often
        # finishes at once.
        pending = (W0, S0)
    iterations = 0
    status = "max_iterations"
    s = slacks(x)
    while True:
        p = int(np.argmin(s))
        if not s[p] < -tol:
            status = "solved"
            break
        if iterations >= max_iter:
            break
        if pending is not None:
            W0, S0 = pending
            pending = None
            try:
                Sinv[:q, :q] = np.linalg.inv(S0)
            except (np.linalg.LinAlgError, ValueError):
                # Should not happen (S0 was factorised); restart cold.
                x, q, active = -_chol_solve(factor, g), 0, []
                s = slacks(x)
                continue
            VT[:q] = np.asarray(_trsm(1.0, factor, W0, lower=1, trans_a=1)).T
        n_p = normal(p)
        v = _chol_solve(factor, n_p)
        vn = float(v @ n_p)
        lam_p = 0.0
        s_p = float(s[p])
        added = False
        while not added:
            if iterations >= max_iter:
                break
            iterations += 1
            if q:
                b = VT[:q] @ n_p
                r = Sinv[:q, :q] @ b
                z = v - r @ VT[:q]
                zn = vn - float(b @ r)
            else:
                r = np.zeros(0)
                z = v
                zn = vn
            # Full step: makes constraint p exact. Below this curvature z is taken as zero
            # (n_p depends linearly on the active normals).
            t2 = -s_p / zn if zn > 1e-12 * vn and q < n else np.inf
            k, t1 = -1, np.inf
            pos = np.flatnonzero(r > 0.0)
            if pos.shape[0]:
                ratios = lam[pos] / r[pos]
                j = int(np.argmin(ratios))
                k, t1 = int(pos[j]), float(ratios[j])
            t = min(t1, t2)
            if not t < np.inf:
                return ActiveSetResult(
                    "infeasible", x, iterations, q, np.zeros(m), np.zeros(n), float(-s[p])
                )
            if t2 < np.inf:
                x = x + t * z
                s_p += t * zn
            lam[:q] -= t * r
            lam_p += t
            if t2 <= t1:
                if q == cap:
                    cap = min(n, 2 * cap)
                    VT = np.concatenate([VT[:q], np.empty((cap - q, n))])
                    Sn = np.empty((cap, cap))
                    Sn[:q, :q] = Sinv[:q, :q]
                    Sinv = Sn
                    lam = np.concatenate([lam[:q], np.empty(cap - q)])
                # Add p. Bordering: with w = S^-1 b = r and delta = zn,
                # [[S, b], [b', c]]^-1 = [[S^-1 + r r'/delta, -r/delta], [-r'/delta, 1/delta]].
                if q:
                    Sinv[:q, :q] += np.outer(r, r / zn)
                    Sinv[:q, q] = Sinv[q, :q] = -r / zn
                Sinv[q, q] = 1.0 / zn
                VT[q] = v
                lam[q] = lam_p
                q += 1
                active.append(p)
                added = True
            else:
                # Drop the active constraint whose multiplier reached zero; keep adding p.
                # Inverse of S without row/column k: M_-k,-k - M_-k,k M_k,-k / M_kk.
                keep = np.arange(q) != k
                col = Sinv[:q, k][keep]
                Sinv[: q - 1, : q - 1] = (
                    Sinv[:q, :q][np.ix_(keep, keep)] - np.outer(col, col) / Sinv[k, k]
                )
                VT[k : q - 1] = VT[k + 1 : q].copy()
                lam[k : q - 1] = lam[k + 1 : q].copy()
                q -= 1
                del active[k]
        if not added:
            break
        s = slacks(x)
    lam = lam[:q]
    # Multipliers in the H x + g + C' z_in + z_box = 0 convention: a lower bound's normal is
    # +row, its multiplier enters with a minus sign; an upper bound's with a plus sign.
    z_rows = np.zeros(mn)
    for i, lam_i in zip(active, lam, strict=True):
        if i < mn:
            z_rows[i] -= lam_i
        else:
            z_rows[i - mn] += lam_i
    viol = float(max(0.0, -float(np.min(slacks(x)))))
    return ActiveSetResult(status, x, iterations, len(active), z_rows[:m], z_rows[m:], viol)
