"""Convex QP layer: the only module that imports a QP solver (proxsuite, piqp, daqp).

Problem (all parts but ``H`` and ``g`` optional)::

    minimise    1/2 x' H x + g' x
    subject to  A x = b                      (n_eq rows)
                l <= C x <= u                (n_in rows, two-sided, +-inf allowed)
                x_lower <= x <= x_upper      (box, +-inf allowed)

Matrices are dense numpy arrays, or ``scipy.sparse`` matrices for the sparse solvers
(all of ``H``, ``A``, ``C`` sparse then). Absent bounds are ``+-inf``, never ``+-1e20``:
piqp counts 1e20 as a finite bound and runs into its iteration limit.

Dual convention of `QpSolution` (every backend mapped to it)::

    H x + g + A' y_eq + C' z_in + z_box = 0

with ``z_in > 0`` where an upper bound is active and ``< 0`` where a lower bound is.

`QpSolver` keeps the backend's solver object and, while the problem keeps its dimensions
(and, for sparse problems, its sparsity pattern), only updates the data. Warm starts are off
by default: in closed loop with contact switches a warm-started proxsuite ran into its
iteration limit on most stepping MPC QPs (see stack-notes.md).

daqp (DAQP 0.11, a dual active-set method in C) is dense only (sparse problems are
densified) and needs H positive definite; it is exact once it stops (no residual
tolerance, only ``eps_abs`` on its normalised rows), and its warm start is a guessed active
set, which changes the iteration count but never the optimum. Given a problem's
`LeastDistanceForm` (the caller's factor of H^-1 and the constraint rows in it) it skips
DAQP's own O(n^3) transformation and first checks the unconstrained minimiser; that is the
MPC's path.

Neither proxsuite 0.8 nor piqp 0.7 has a wall-time limit; ``max_iter`` is the cap.
proxsuite stops on primal/dual residuals alone by default and then may return a point 1e-5
away from the optimum (duality gap 4e-5 on a 3-variable problem); the duality-gap check is
therefore on by default for both backends.
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Final, TypeAlias

import daqp
import numba
import numpy as np
import numpy.typing as npt
import piqp
import scipy.sparse as sp
from proxsuite import proxqp

FloatArray = npt.NDArray[np.float64]
# A dense FloatArray or a scipy.sparse matrix (scipy ships no type stubs here).
Matrix: TypeAlias = Any

BACKENDS: Final[tuple[str, ...]] = ("proxsuite", "piqp", "daqp")

_PROXSUITE_STATUS: Final[dict[Any, str]] = {
    proxqp.PROXQP_SOLVED: "solved",
    proxqp.PROXQP_MAX_ITER_REACHED: "max_iterations",
    proxqp.PROXQP_PRIMAL_INFEASIBLE: "primal_infeasible",
    proxqp.PROXQP_DUAL_INFEASIBLE: "dual_infeasible",
    proxqp.PROXQP_SOLVED_CLOSEST_PRIMAL_FEASIBLE: "closest_primal_feasible",
    proxqp.PROXQP_NOT_RUN: "not_run",
}
_PIQP_STATUS: Final[dict[Any, str]] = {
    piqp.PIQP_SOLVED: "solved",
    piqp.PIQP_MAX_ITER_REACHED: "max_iterations",
    piqp.PIQP_PRIMAL_INFEASIBLE: "primal_infeasible",
    piqp.PIQP_DUAL_INFEASIBLE: "dual_infeasible",
    piqp.PIQP_NUMERICS: "numerical_error",
    piqp.PIQP_UNSOLVED: "unsolved",
    piqp.PIQP_INVALID_SETTINGS: "invalid_settings",
}
# DAQP's exit flags (constants.h of DAQP 0.11). 2 is "optimal with soft constraints
# violated": no soft constraints are ever declared here. -2 (cycling) and -5 (H not positive
# definite) are numerical failures; -6: the guessed active set had more linearly independent
# constraints than variables.
_DAQP_STATUS: Final[dict[int, str]] = {
    1: "solved",
    2: "solved",
    -1: "primal_infeasible",
    -2: "numerical_error",
    -3: "dual_infeasible",
    -4: "max_iterations",
    -5: "numerical_error",
    -6: "numerical_error",
    -7: "max_iterations",
    -8: "invalid_settings",
}
# DAQP's constraint sense flags: active (a warm-start guess), active at the lower bound,
# equality.
_DAQP_ACTIVE: Final = 1
_DAQP_LOWER: Final = 2
_DAQP_EQUALITY: Final = 5
# Rounds of the least-distance solve on a subset of W's rows (`QpSolver`), the last with
# every row. The subset starts with the rows violated at the unconstrained minimiser and
# takes in those its optimum violates: on the package transfer's 465 recorded MPC updates
# (HECTOR, 760 rows by 200 variables at the drop) at most 3 rounds were needed.
_SUBSET_ROUNDS: Final = 6


def _is_sparse(M: object) -> bool:
    return bool(sp.issparse(M))


def _check_vector(name: str, v: FloatArray | None, size: int) -> None:
    if v is None:
        return
    if v.shape != (size,):
        raise ValueError(f"QpProblem.{name} has shape {v.shape}, expected ({size},)")


@dataclass(frozen=True, slots=True)
class QpProblem:
    """A convex QP: ``min 1/2 x'Hx + g'x`` s.t. ``Ax = b``, ``l <= Cx <= u``, box bounds.

    Shapes: ``H`` (n, n) symmetric positive semidefinite, ``g`` (n,), ``A`` (n_eq, n),
    ``b`` (n_eq,), ``C`` (n_in, n), ``l``/``u`` (n_in,), ``x_lower``/``x_upper`` (n,).
    ``A``/``b`` come together, ``C`` needs at least one of ``l``/``u`` (the missing side is
    taken as infinite); a box needs at least one of ``x_lower``/``x_upper``. Use ``+-inf`` for
    absent bounds. Matrices are dense arrays, or all scipy.sparse for the sparse solvers.
    """

    H: Matrix
    g: FloatArray
    A: Matrix | None = None
    b: FloatArray | None = None
    C: Matrix | None = None
    l: FloatArray | None = None
    u: FloatArray | None = None
    x_lower: FloatArray | None = None
    x_upper: FloatArray | None = None

    def __post_init__(self) -> None:
        n = self.g.shape[0]
        if self.g.ndim != 1:
            raise ValueError(f"QpProblem.g must be 1-D, got shape {self.g.shape}")
        if self.H.shape != (n, n):
            raise ValueError(f"QpProblem.H has shape {self.H.shape}, expected ({n}, {n})")
        if (self.A is None) != (self.b is None):
            raise ValueError("QpProblem.A and QpProblem.b must be given together")
        if self.A is not None:
            assert self.b is not None
            if self.A.shape != (self.b.shape[0], n):
                raise ValueError(f"QpProblem.A has shape {self.A.shape}, expected (n_eq, {n})")
            _check_vector("b", self.b, self.A.shape[0])
        if self.C is not None:
            if self.l is None and self.u is None:
                raise ValueError("QpProblem.C needs l and/or u")
            if self.C.ndim != 2 or self.C.shape[1] != n:
                raise ValueError(f"QpProblem.C has shape {self.C.shape}, expected (n_in, {n})")
            _check_vector("l", self.l, self.C.shape[0])
            _check_vector("u", self.u, self.C.shape[0])
        elif self.l is not None or self.u is not None:
            raise ValueError("QpProblem.l/u given without C")
        _check_vector("x_lower", self.x_lower, n)
        _check_vector("x_upper", self.x_upper, n)
        sparse = [_is_sparse(M) for M in (self.H, self.A, self.C) if M is not None]
        if any(sparse) and not all(sparse):
            raise ValueError("QpProblem: H, A, C must be all dense or all scipy.sparse")

    @property
    def n(self) -> int:
        """Number of variables."""
        return int(self.g.shape[0])

    @property
    def n_eq(self) -> int:
        """Number of equality rows."""
        return 0 if self.A is None else int(self.A.shape[0])

    @property
    def n_in(self) -> int:
        """Number of two-sided inequality rows (the box not counted)."""
        return 0 if self.C is None else int(self.C.shape[0])

    @property
    def has_box(self) -> bool:
        """Whether box bounds on x are given."""
        return self.x_lower is not None or self.x_upper is not None

    @property
    def is_sparse(self) -> bool:
        """Whether the matrices are scipy.sparse."""
        return _is_sparse(self.H)

    def objective(self, x: FloatArray) -> float:
        """``1/2 x'Hx + g'x`` at x (n,)."""
        return float(0.5 * x @ (self.H @ x) + self.g @ x)


@dataclass(frozen=True, slots=True)
class QpSettings:
    """Solver settings shared by the backends.

    ``eps_abs``/``eps_rel`` bound the primal and dual residuals, ``eps_gap_abs``/
    ``eps_gap_rel`` the duality gap (checked when ``check_duality_gap``). ``max_iter`` caps
    the iterations (a problem that hits it is a failure). ``warm_start`` starts from the
    previous solution (proxsuite), or for daqp from the ``active_hint`` given to
    `QpSolver.solve`, else from the previous solution's active set (piqp is an
    interior-point method and always starts cold).
    ``preconditioner`` lets the backend equilibrate the problem (proxsuite's Ruiz scaling costs
    about 1 ms on a 200-variable dense problem); ``update_preconditioner`` recomputes it when
    a re-used proxsuite solver gets new matrices. ``scaling`` applies a Jacobi scaling
    x = D y, D = diag(H)^-1/2, before the backend (cheap, O(n^2)).
    ``eps_primal_inf``/``eps_dual_inf`` are the infeasibility-detection thresholds
    (None: the backend's; proxsuite's default 1e-4 declared feasible MPC problems infeasible).
    ``max_iter_in`` caps proxsuite's inner iterations per outer one (None: its 1500): on an
    infeasible MPC problem that it fails to detect, 100 outer x 1500 inner iterations took 14 s,
    while feasible ones never needed more than 14 in all. ``complementarity_tol``: a backend
    solution whose complementarity residual max_j |z_j| * (distance of row j to the bound its
    multiplier refers to) exceeds tol * (1 + |objective|) is reported "inaccurate" (not ok).
    proxsuite 0.8 warm-started after an update returned feasible but non-optimal points as
    "solved" (objective -2.75 instead of -7.61); on 200 consecutive WBC-like problems the
    relative residual was <= 1e-8 for every correct solution and >= 5e-4 for every wrong one
    (x off by >= 1e-2). Distances are capped at 1e6. None skips the check.
    """

    eps_abs: float = 1e-8
    eps_rel: float = 0.0
    check_duality_gap: bool = True
    eps_gap_abs: float = 1e-8
    eps_gap_rel: float = 0.0
    max_iter: int = 200
    warm_start: bool = False
    preconditioner: bool = True
    update_preconditioner: bool = True
    scaling: bool = False
    eps_primal_inf: float | None = None
    eps_dual_inf: float | None = None
    max_iter_in: int | None = None
    complementarity_tol: float | None = 1e-4

    def __post_init__(self) -> None:
        if not (self.eps_abs > 0 and self.eps_rel >= 0):
            raise ValueError("QpSettings: eps_abs must be > 0 and eps_rel >= 0")
        if not (self.eps_gap_abs > 0 and self.eps_gap_rel >= 0):
            raise ValueError("QpSettings: eps_gap_abs must be > 0 and eps_gap_rel >= 0")
        if self.max_iter < 1:
            raise ValueError("QpSettings.max_iter must be >= 1")
        if self.max_iter_in is not None and self.max_iter_in < 1:
            raise ValueError("QpSettings.max_iter_in must be >= 1")
        for name in ("eps_primal_inf", "eps_dual_inf"):
            v = getattr(self, name)
            if v is not None and not v > 0:
                raise ValueError(f"QpSettings.{name} must be > 0")


@dataclass(frozen=True, slots=True)
class QpSolution:
    """Result of one solve.

    ``x`` (n,) is the backend's last iterate (meaningful only when ``ok``). ``status`` is one
    of "solved", "max_iterations", "primal_infeasible", "dual_infeasible", "inaccurate",
    "closest_primal_feasible", "numerical_error", "unsolved", "invalid_settings", "not_run",
    "non_finite"; ``ok`` is True only for "solved" with a finite x. ``solve_time_s`` is the
    wall time of the solve call (scaling, the backend's data update/setup and solve; s), of
    which ``setup_time_s`` was the backend's update/setup. ``iterations``: 0 when the
    unconstrained minimiser met every bound on daqp's least-distance path. ``active_set``:
    True from `LeanDenseQp` (DAQP's dual active-set method, called directly), False from
    `QpSolver`. Residuals are
    infinity norms (the backend's; on daqp's least-distance path the dual residual is zero by
    construction up to rounding). Duals follow ``H x + g + A'y_eq + C'z_in + z_box = 0``.
    """

    x: FloatArray
    status: str
    ok: bool
    iterations: int
    solve_time_s: float
    setup_time_s: float
    primal_residual: float
    dual_residual: float
    objective: float
    backend: str
    reused: bool
    active_set: bool
    y_eq: FloatArray = field(repr=False)
    z_in: FloatArray = field(repr=False)
    z_box: FloatArray = field(repr=False)


@dataclass(slots=True)
class _Raw:
    """What a backend returns, on the problem it was given (possibly scaled)."""

    x: FloatArray
    status: str
    iterations: int
    setup_time_s: float
    primal_residual: float
    dual_residual: float
    reused: bool
    y_eq: FloatArray
    z_in: FloatArray
    z_box: FloatArray


def _inf_fill(v: FloatArray | None, size: int, sign: float) -> FloatArray:
    return np.full(size, sign * math.inf) if v is None else v


def _structure_key(p: QpProblem) -> tuple[object, ...]:
    key: tuple[object, ...] = (p.is_sparse, p.n, p.n_eq, p.n_in, p.has_box)
    if p.is_sparse:
        for M in (p.H, p.A, p.C):
            if M is None:
                key += (None,)
            else:
                Mc = sp.csc_matrix(M)
                key += (Mc.indptr.tobytes(), Mc.indices.tobytes())
    return key


def _jacobi_scaled(p: QpProblem) -> tuple[QpProblem, FloatArray]:
    """The problem in y with x = D y, D = diag(H)^-1/2 (1 where H_ii <= 0), and D (n,)."""
    h = np.asarray(p.H.diagonal(), dtype=np.float64)
    d = np.ones_like(h)
    pos = h > 0.0
    d[pos] = 1.0 / np.sqrt(h[pos])
    if p.is_sparse:
        D = sp.diags(d, format="csc")
        H = D @ p.H @ D
        A = p.A @ D if p.A is not None else None
        C = p.C @ D if p.C is not None else None
    else:
        H = p.H * d[:, None] * d[None, :]
        A = p.A * d[None, :] if p.A is not None else None
        C = p.C * d[None, :] if p.C is not None else None
    lb = p.x_lower / d if p.x_lower is not None else None
    ub = p.x_upper / d if p.x_upper is not None else None
    scaled = QpProblem(H=H, g=p.g * d, A=A, b=p.b, C=C, l=p.l, u=p.u, x_lower=lb, x_upper=ub)
    return scaled, d


def _complementarity(p: QpProblem, x: FloatArray, z_in: FloatArray, z_box: FloatArray) -> float:
    """max_j |z_j| times the distance of row j to the bound its multiplier's sign refers to
    (z > 0: upper, z < 0: lower), distances capped at 1e6 so that the 1e-200 multipliers
    some backends leave on infinite bounds do not count."""
    worst = 0.0
    pairs = []
    if p.C is not None:
        Cx = p.C @ x
        lo = p.l if p.l is not None else np.full(p.n_in, -math.inf)
        hi = p.u if p.u is not None else np.full(p.n_in, math.inf)
        pairs.append((Cx, lo, hi, z_in))
    if p.has_box:
        lo = p.x_lower if p.x_lower is not None else np.full(p.n, -math.inf)
        hi = p.x_upper if p.x_upper is not None else np.full(p.n, math.inf)
        pairs.append((x, lo, hi, z_box))
    for v, lo, hi, z in pairs:
        up = np.maximum(z, 0.0) * np.minimum(hi - v, 1e6)
        down = np.maximum(-z, 0.0) * np.minimum(v - lo, 1e6)
        worst = max(worst, float(np.max(up, initial=0.0)), float(np.max(down, initial=0.0)))
    return worst


@functools.cache
def _identity(n: int) -> FloatArray:
    """The least-distance form's Hessian, one per size: a fresh np.eye(200) costs 0.1-0.2 ms
    (the 320 kB come from mmap, page-faulted in). DAQP only reads it (its setup copies what
    it keeps; checked: unchanged after setups and solves), but its wrapper asks for a
    writable buffer."""
    return np.eye(n)


@functools.cache
def _zeros(n: int) -> FloatArray:
    """The least-distance form's linear term (see `_identity`)."""
    return np.zeros(n)


def _violation(p: QpProblem, x: FloatArray) -> float:
    """Largest violation of p's constraints at x (inf norm, >= 0)."""
    v = 0.0
    if p.A is not None:
        assert p.b is not None
        v = max(v, float(np.max(np.abs(p.A @ x - p.b), initial=0.0)))
    if p.C is not None:
        Cx = p.C @ x
        if p.l is not None:
            v = max(v, float(np.max(p.l - Cx, initial=0.0)))
        if p.u is not None:
            v = max(v, float(np.max(Cx - p.u, initial=0.0)))
    if p.x_lower is not None:
        v = max(v, float(np.max(p.x_lower - x, initial=0.0)))
    if p.x_upper is not None:
        v = max(v, float(np.max(x - p.x_upper, initial=0.0)))
    return v


def constraint_id(m: int, n: int, row: npt.ArrayLike, upper: npt.ArrayLike) -> npt.NDArray[np.intp]:
    """Ids of one-sided constraints of a QP with m rows in C and n variables: ``row`` < m is
    a row of C, m + i the box on x_i; ``upper`` selects the upper bound (id + m + n), else
    the lower."""
    r = np.asarray(row, dtype=np.intp)
    return np.where(np.asarray(upper, dtype=bool), (m + n) + r, r)


@dataclass(frozen=True, slots=True)
class LeastDistanceForm:
    """A dense QP without equalities in least-distance form, for daqp.

    ``x_u`` (n,) is the unconstrained minimiser -H^-1 g. With a square factor U (n, n) of
    the inverse Hessian, H^-1 = U U' (e.g. L^-T for H = L L'), and x = x_u + U y, the QP is
    min 1/2 |y|^2 subject to the QP's bounds, shifted by x_u, on the rows of
    W (n_b + n_in, n): U[box_index] (the box on x) above C U, where ``box_index`` are the n_b
    variables with a finite lower or upper bound, in increasing order. ``factor()`` returns
    U, ``rows(idx)`` the rows ``idx`` (increasing) of W; neither is called unless x_u
    violates a bound, since they cost more than x_u, and the solver asks only for the rows
    it needs (`QpSolver`). That is DAQP's own internal form: it reaches it with an O(n^3)
    transformation in plain C (2.5 ms at n = 200), which a caller that knows the structure
    of its problem (cached factor blocks, a block-diagonal C) computes far faster. The
    multipliers of W's rows are the QP's (the same constraints, in y). No array is kept
    after the solve. ``box``: the caller's ``box_index`` when it has it (W was built with
    it): the solver then takes it as given instead of finding the finite bounds itself.
    """

    x_u: FloatArray
    factor: Callable[[], FloatArray]
    rows: Callable[[npt.NDArray[np.intp]], FloatArray]
    box: npt.NDArray[np.integer[Any]] | None = None

    @classmethod
    def from_dense(
        cls,
        x_u: FloatArray,
        U: FloatArray,
        W: FloatArray,
        box: npt.NDArray[np.integer[Any]] | None = None,
    ) -> LeastDistanceForm:
        """The form of U and the whole W given as arrays."""
        return cls(x_u=x_u, factor=lambda: U, rows=lambda idx: W[idx], box=box)


class QpSolver:
    """Stateful QP solver: keeps the backend object and re-uses it while dimensions hold.

    ``backend`` is "proxsuite", "piqp" or "daqp". Dense problems go to the dense solvers,
    sparse problems to the sparse ones (proxsuite's sparse solver has no box: the box becomes
    inequality rows there; daqp has no sparse solver: the matrices are densified).
    """

    def __init__(self, backend: str = "proxsuite", settings: QpSettings | None = None) -> None:
        if backend not in BACKENDS:
            raise ValueError(f"unknown QP backend {backend!r}, expected one of {BACKENDS}")
        self.backend = backend
        self.settings = settings if settings is not None else QpSettings()
        self._solver: Any = None
        self._key: tuple[object, ...] | None = None
        self._has_result = False

    def reset(self) -> None:
        """Forget the solver object (the next solve sets it up from scratch)."""
        self._solver = None
        self._key = None
        self._has_result = False

    def solve(
        self,
        problem: QpProblem,
        active_hint: npt.ArrayLike | None = None,
        least_distance: LeastDistanceForm | None = None,
    ) -> QpSolution:
        """Solve ``problem``; never raises on solver failure (check ``ok``/``status``).

        ``active_hint``: guessed active constraint ids (see `constraint_id`;
        `active_constraint_ids` of a previous solution), daqp's starting active set with
        ``settings.warm_start`` (other backends ignore it). ``least_distance``: the
        problem's `LeastDistanceForm` if the caller has it (daqp only, dense, no
        equalities); ``settings.scaling`` is then not applied (DAQP normalises W's rows).
        """
        s = self.settings
        t0 = time.perf_counter()
        p = problem
        if least_distance is not None:
            if self.backend != "daqp" or p.is_sparse or p.n_eq:
                raise ValueError("least_distance needs the daqp backend and a dense QP without A")
            return self._solve_daqp_least_distance(p, least_distance, active_hint, t0)
        p, d = _jacobi_scaled(problem) if s.scaling else (problem, None)
        key = _structure_key(p)
        reuse = self._solver is not None and key == self._key
        if self.backend == "proxsuite":
            if p.is_sparse:
                raw = self._solve_proxsuite_sparse(p, reuse, key)
            else:
                raw = self._solve_proxsuite_dense(p, reuse, key)
        elif self.backend == "daqp":
            raw = self._solve_daqp(p, key, active_hint)
        else:
            raw = self._solve_piqp(p, reuse, key)
        t1 = time.perf_counter()
        x = raw.x * d if d is not None else raw.x
        z_box = raw.z_box / d if d is not None else raw.z_box
        finite = bool(np.all(np.isfinite(x)))
        status = raw.status
        if status == "solved" and not finite:
            status = "non_finite"
        objective = problem.objective(x) if finite else math.nan
        if status == "solved" and s.complementarity_tol is not None:
            comp = _complementarity(problem, x, raw.z_in, z_box)
            if comp > s.complementarity_tol * (1.0 + abs(objective)):
                status = "inaccurate"
        ok = status == "solved"
        # A failed iterate is a bad warm start: the next solve starts cold.
        self._has_result = ok
        return QpSolution(
            x=x,
            status=status,
            ok=ok,
            iterations=raw.iterations,
            solve_time_s=t1 - t0,
            setup_time_s=raw.setup_time_s,
            primal_residual=raw.primal_residual,
            dual_residual=raw.dual_residual,
            objective=objective,
            backend=self.backend,
            reused=raw.reused,
            active_set=False,
            y_eq=raw.y_eq,
            z_in=raw.z_in,
            z_box=z_box,
        )

    # --- proxsuite -------------------------------------------------------------------------

    def _configure_proxsuite(self, qp: Any) -> None:
        s = self.settings
        qp.settings.eps_abs = s.eps_abs
        qp.settings.eps_rel = s.eps_rel
        qp.settings.check_duality_gap = s.check_duality_gap
        qp.settings.eps_duality_gap_abs = s.eps_gap_abs
        qp.settings.eps_duality_gap_rel = s.eps_gap_rel
        qp.settings.max_iter = s.max_iter
        if s.eps_primal_inf is not None:
            qp.settings.eps_primal_inf = s.eps_primal_inf
        if s.eps_dual_inf is not None:
            qp.settings.eps_dual_inf = s.eps_dual_inf
        if s.max_iter_in is not None:
            qp.settings.max_iter_in = s.max_iter_in
        qp.settings.verbose = False
        qp.settings.compute_timings = False

    def _set_proxsuite_guess(self, qp: Any) -> None:
        if self.settings.warm_start and self._has_result:
            qp.settings.initial_guess = proxqp.InitialGuess.WARM_START_WITH_PREVIOUS_RESULT
        else:
            qp.settings.initial_guess = proxqp.InitialGuess.EQUALITY_CONSTRAINED_INITIAL_GUESS

    def _proxsuite_raw(self, qp: Any, p: QpProblem, n_in: int, setup: float, reuse: bool) -> _Raw:
        r = qp.results
        z = np.asarray(r.z, dtype=np.float64)
        n = p.n
        return _Raw(
            x=np.array(r.x, dtype=np.float64),
            status=_PROXSUITE_STATUS.get(r.info.status, str(r.info.status)),
            iterations=int(r.info.iter),
            setup_time_s=setup,
            primal_residual=float(r.info.pri_res),
            dual_residual=float(r.info.dua_res),
            reused=reuse,
            y_eq=np.array(r.y, dtype=np.float64).reshape(-1)[: p.n_eq],
            z_in=z[:n_in].copy(),
            z_box=z[n_in : n_in + n].copy() if p.has_box else np.zeros(n),
        )

    def _solve_proxsuite_dense(self, p: QpProblem, reuse: bool, key: tuple[object, ...]) -> _Raw:
        s = self.settings
        n, n_in = p.n, p.n_in
        l = _inf_fill(p.l, n_in, -1.0) if p.C is not None else None
        u = _inf_fill(p.u, n_in, 1.0) if p.C is not None else None
        lb = _inf_fill(p.x_lower, n, -1.0) if p.has_box else None
        ub = _inf_fill(p.x_upper, n, 1.0) if p.has_box else None
        t0 = time.perf_counter()
        if reuse:
            qp = self._solver
            self._set_proxsuite_guess(qp)
            upd = s.preconditioner and s.update_preconditioner
            if p.has_box:
                qp.update(p.H, p.g, p.A, p.b, p.C, l, u, lb, ub, update_preconditioner=upd)
            else:
                qp.update(p.H, p.g, p.A, p.b, p.C, l, u, update_preconditioner=upd)
        else:
            qp = proxqp.dense.QP(n, p.n_eq, n_in, p.has_box)
            self._configure_proxsuite(qp)
            qp.settings.initial_guess = proxqp.InitialGuess.EQUALITY_CONSTRAINED_INITIAL_GUESS
            pre = s.preconditioner
            if p.has_box:
                qp.init(p.H, p.g, p.A, p.b, p.C, l, u, lb, ub, compute_preconditioner=pre)
            else:
                qp.init(p.H, p.g, p.A, p.b, p.C, l, u, compute_preconditioner=pre)
            self._solver, self._key = qp, key
        t1 = time.perf_counter()
        qp.solve()
        return self._proxsuite_raw(qp, p, n_in, t1 - t0, reuse)

    def _solve_proxsuite_sparse(self, p: QpProblem, reuse: bool, key: tuple[object, ...]) -> _Raw:
        # proxsuite's sparse solver has no box: stack it under C as identity rows.
        s = self.settings
        n = p.n
        C_rows: list[Any] = []
        l_parts: list[FloatArray] = []
        u_parts: list[FloatArray] = []
        if p.C is not None:
            C_rows.append(p.C)
            l_parts.append(_inf_fill(p.l, p.n_in, -1.0))
            u_parts.append(_inf_fill(p.u, p.n_in, 1.0))
        if p.has_box:
            C_rows.append(sp.identity(n, format="csc"))
            l_parts.append(_inf_fill(p.x_lower, n, -1.0))
            u_parts.append(_inf_fill(p.x_upper, n, 1.0))
        C = sp.csc_matrix(sp.vstack(C_rows)) if C_rows else None
        l = np.concatenate(l_parts) if C_rows else None
        u = np.concatenate(u_parts) if C_rows else None
        H = sp.csc_matrix(p.H)
        A = sp.csc_matrix(p.A) if p.A is not None else None
        n_c = 0 if C is None else C.shape[0]
        t0 = time.perf_counter()
        if reuse:
            qp = self._solver
            self._set_proxsuite_guess(qp)
            upd = s.preconditioner and s.update_preconditioner
            qp.update(H, p.g, A, p.b, C, l, u, update_preconditioner=upd)
        else:
            qp = proxqp.sparse.QP(n, p.n_eq, n_c)
            self._configure_proxsuite(qp)
            qp.settings.initial_guess = proxqp.InitialGuess.EQUALITY_CONSTRAINED_INITIAL_GUESS
            qp.init(H, p.g, A, p.b, C, l, u, compute_preconditioner=s.preconditioner)
            self._solver, self._key = qp, key
        t1 = time.perf_counter()
        qp.solve()
        raw = self._proxsuite_raw(qp, p, p.n_in, t1 - t0, reuse)
        if p.has_box:
            z = np.asarray(qp.results.z, dtype=np.float64)
            raw.z_box = z[p.n_in : p.n_in + n].copy()
        return raw

    # --- piqp ------------------------------------------------------------------------------

    def _solve_piqp(self, p: QpProblem, reuse: bool, key: tuple[object, ...]) -> _Raw:
        s = self.settings
        n, n_in = p.n, p.n_in
        l = _inf_fill(p.l, n_in, -1.0) if p.C is not None else None
        u = _inf_fill(p.u, n_in, 1.0) if p.C is not None else None
        lb = _inf_fill(p.x_lower, n, -1.0) if p.has_box else None
        ub = _inf_fill(p.x_upper, n, 1.0) if p.has_box else None
        H: Any
        A: Any
        C: Any
        if p.is_sparse:
            # piqp reads the upper triangle of P only.
            H = sp.triu(p.H, format="csc")
            A = sp.csc_matrix(p.A) if p.A is not None else None
            C = sp.csc_matrix(p.C) if p.C is not None else None
        else:
            # Column-major avoids a copy inside the binding; H is symmetric so H.T is free.
            H = p.H.T
            A = np.asfortranarray(p.A) if p.A is not None else None
            C = np.asfortranarray(p.C) if p.C is not None else None
        t0 = time.perf_counter()
        if reuse:
            solver = self._solver
            solver.update(H, p.g, A, p.b, C, l, u, lb, ub)
        else:
            solver = piqp.SparseSolver() if p.is_sparse else piqp.DenseSolver()
            ps = solver.settings
            ps.eps_abs = s.eps_abs
            ps.eps_rel = s.eps_rel
            ps.check_duality_gap = s.check_duality_gap
            ps.eps_duality_gap_abs = s.eps_gap_abs
            ps.eps_duality_gap_rel = s.eps_gap_rel
            ps.max_iter = s.max_iter
            if s.eps_primal_inf is not None:
                ps.eps_primal_inf = s.eps_primal_inf
            if s.eps_dual_inf is not None:
                ps.eps_dual_inf = s.eps_dual_inf
            if not s.preconditioner:
                ps.preconditioner_iter = 0
            ps.verbose = False
            ps.compute_timings = False
            solver.setup(H, p.g, A, p.b, C, l, u, lb, ub)
            self._solver, self._key = solver, key
        t1 = time.perf_counter()
        status = solver.solve()
        r = solver.result
        z_in = np.asarray(r.z_u, dtype=np.float64) - np.asarray(r.z_l, dtype=np.float64)
        if p.has_box:
            z_box = np.asarray(r.z_bu, dtype=np.float64) - np.asarray(r.z_bl, dtype=np.float64)
        else:
            z_box = np.zeros(n)
        return _Raw(
            x=np.array(r.x, dtype=np.float64),
            status=_PIQP_STATUS.get(status, str(status)),
            iterations=int(r.info.iter),
            setup_time_s=t1 - t0,
            primal_residual=float(r.info.primal_res),
            dual_residual=float(r.info.dual_res),
            reused=reuse,
            y_eq=np.array(r.y, dtype=np.float64).reshape(-1)[: p.n_eq],
            z_in=z_in[:n_in],
            z_box=z_box,
        )

    # --- daqp ------------------------------------------------------------------------------

    def _daqp_sense(
        self,
        p: QpProblem,
        n_box: int,
        hint: npt.ArrayLike | None,
        lower: FloatArray,
        upper: FloatArray,
    ) -> npt.NDArray[np.intc]:
        """DAQP's sense flags: equality rows, and with ``warm_start`` the guessed active set
        (``hint``, else the previous solution's when the rows are the same), on finite bounds
        only (``lower``/``upper`` of DAQP's rows)."""
        s = self.settings
        m, n = p.n_in, p.n
        k = n_box + m  # inequality rows
        sense = np.zeros(k + p.n_eq, dtype=np.intc)
        sense[k:] = _DAQP_EQUALITY
        if not s.warm_start:
            return sense
        if hint is None:
            prev = self._solver
            if isinstance(prev, np.ndarray) and self._has_result and prev.shape[0] == k:
                sense[:k] = prev
        else:
            # Hint ids: j < m is the lower bound of C's row j, m + i the lower bound of x_i,
            # the same plus (m + n) the upper bound. DAQP's rows: the box first, then C's.
            ids = np.asarray(hint, dtype=np.intp).reshape(-1)
            ids = ids[(ids >= 0) & (ids < 2 * (m + n))]
            up = ids >= m + n
            j = np.where(up, ids - (m + n), ids)
            is_row = j < m
            idx = np.where(is_row, n_box + j, j - m)
            keep = is_row | (n_box > 0)
            sense[idx[keep]] = np.where(up[keep], _DAQP_ACTIVE, _DAQP_ACTIVE | _DAQP_LOWER)
        # A guess on an infinite bound would pin the row at infinity.
        on_lower = (sense[:k] & _DAQP_LOWER) > 0
        finite = np.where(on_lower, np.isfinite(lower[:k]), np.isfinite(upper[:k]))
        sense[:k][~finite] = 0
        return sense

    def _solve_daqp(
        self, p: QpProblem, key: tuple[object, ...], hint: npt.ArrayLike | None
    ) -> _Raw:
        # One-shot daqp.solve rather than a re-used daqp.Model: H changes at every MPC update
        # anyway, and Model.update always forms DAQP's whole transformed problem (H^-1/2 and
        # the constraint rows in it: 2.5 ms at n = 200), while daqp.solve first checks the
        # unconstrained minimiser (one Cholesky factorisation: 0.5 ms).
        s = self.settings
        n, m, n_eq = p.n, p.n_in, p.n_eq

        def dense(M: Matrix) -> FloatArray:
            out = M.toarray() if p.is_sparse else M
            return np.ascontiguousarray(out, dtype=np.float64)

        # DAQP's rows: n simple bounds on x (when there is a box), C's rows, A's rows
        # (equalities, l = u = b).
        n_box = n if p.has_box else 0
        mats = [dense(M) for M in (p.C, p.A) if M is not None]
        A_all = (mats[0] if len(mats) == 1 else np.vstack(mats)) if mats else np.zeros((0, n))
        upper: list[FloatArray] = []
        lower: list[FloatArray] = []
        if p.has_box:
            upper.append(_inf_fill(p.x_upper, n, 1.0))
            lower.append(_inf_fill(p.x_lower, n, -1.0))
        if p.C is not None:
            upper.append(_inf_fill(p.u, m, 1.0))
            lower.append(_inf_fill(p.l, m, -1.0))
        if p.A is not None:
            assert p.b is not None
            upper.append(p.b)
            lower.append(p.b)
        bu = np.ascontiguousarray(np.concatenate(upper) if upper else np.zeros(0))
        bl = np.ascontiguousarray(np.concatenate(lower) if lower else np.zeros(0))
        sense = self._daqp_sense(p, n_box, hint, bl, bu)
        # DAQP reads as many entries of each array as it has rows: never pass a short one.
        if not (bu.shape == bl.shape == sense.shape == (n_box + A_all.shape[0],)):
            raise AssertionError("daqp: inconsistent row counts")
        if np.any(bl > bu):
            # DAQP does not check l <= u: with an inverted row it can report "solved" at a
            # point 50 N off the bounds (the WBC QP with f_min > f_max).
            self._solver, self._key = None, None
            return _Raw(
                x=np.full(n, math.nan),
                status="primal_infeasible",
                iterations=0,
                setup_time_s=0.0,
                primal_residual=math.inf,
                dual_residual=math.inf,
                reused=False,
                y_eq=np.zeros(n_eq),
                z_in=np.zeros(m),
                z_box=np.zeros(n),
            )
        x, _, flag, info = daqp.solve(
            dense(p.H),
            np.ascontiguousarray(p.g, dtype=np.float64),
            A_all,
            bu,
            bl,
            sense,
            primal_tol=s.eps_abs,
            iter_limit=s.max_iter,
        )
        status = _DAQP_STATUS.get(int(flag), f"daqp_{flag}")
        lam = np.asarray(info["lam"], dtype=np.float64)
        x = np.asarray(x, dtype=np.float64)
        if status != "solved":
            # The multipliers of a failed solve are not meaningful (DAQP leaves them unset).
            self._solver, self._key = None, None
            return _Raw(
                x=x,
                status=status,
                iterations=int(info["iterations"]),
                setup_time_s=float(info["setup_time"]),
                primal_residual=math.inf,
                dual_residual=math.inf,
                reused=False,
                y_eq=np.zeros(n_eq),
                z_in=np.zeros(m),
                z_box=np.zeros(n),
            )
        z_box = lam[:n].copy() if p.has_box else np.zeros(n)
        z_in = lam[n_box : n_box + m].copy()
        y_eq = lam[n_box + m :].copy()
        # The active set, for a warm start of the next solve (see _daqp_sense).
        act = np.zeros(n_box + m, dtype=np.intc)
        act[lam[: n_box + m] > 0.0] = _DAQP_ACTIVE
        act[lam[: n_box + m] < 0.0] = _DAQP_ACTIVE | _DAQP_LOWER
        self._solver, self._key = act, key
        stat = p.H @ x + p.g + z_box
        if p.A is not None:
            stat = stat + p.A.T @ y_eq
        if p.C is not None:
            stat = stat + p.C.T @ z_in
        return _Raw(
            x=x,
            status=status,
            iterations=int(info["iterations"]),
            setup_time_s=float(info["setup_time"]),
            primal_residual=_violation(p, x),
            dual_residual=float(np.max(np.abs(stat), initial=0.0)),
            reused=False,
            y_eq=y_eq,
            z_in=z_in,
            z_box=z_box,
        )

    def _solve_daqp_least_distance(
        self, p: QpProblem, form: LeastDistanceForm, hint: npt.ArrayLike | None, t0: float
    ) -> QpSolution:
        s = self.settings
        n, m = p.n, p.n_in
        box: npt.NDArray[np.integer[Any]] = np.zeros(0, dtype=np.intp)
        lo_parts: list[FloatArray] = []
        hi_parts: list[FloatArray] = []
        if p.has_box:
            x_lo = _inf_fill(p.x_lower, n, -1.0)
            x_hi = _inf_fill(p.x_upper, n, 1.0)
            if form.box is not None:
                box = form.box
            else:
                box = np.flatnonzero(np.isfinite(x_lo) | np.isfinite(x_hi))
            lo_parts.append(x_lo[box])
            hi_parts.append(x_hi[box])
        if p.C is not None:
            lo_parts.append(_inf_fill(p.l, m, -1.0))
            hi_parts.append(_inf_fill(p.u, m, 1.0))
        n_b = box.shape[0]
        x_u = form.x_u
        if x_u.shape != (n,):
            raise ValueError(f"LeastDistanceForm.x_u has shape {x_u.shape}, expected ({n},)")
        # Bounds on W y: the QP's bounds minus the rows' values at x_u.
        at_xu = np.empty(n_b + m)
        at_xu[:n_b] = x_u[box]
        if p.C is not None:
            at_xu[n_b:] = p.C @ x_u
        lower = np.concatenate(lo_parts) - at_xu if lo_parts else np.zeros(0)
        upper = np.concatenate(hi_parts) - at_xu if hi_parts else np.zeros(0)
        viol = max(float(lower.max(initial=0.0)), float(-upper.min(initial=0.0)))
        z_in, z_box = np.zeros(m), np.zeros(n)
        if viol > s.eps_abs and np.any(lower > upper):
            # DAQP does not check l <= u (see _solve_daqp).
            self.reset()
            nan = np.full(n, math.nan)
            return self._least_distance_solution(
                p, t0, nan, "primal_infeasible", 0, 0.0, math.inf, z_in, z_box
            )
        if viol <= s.eps_abs:
            # The unconstrained minimiser meets every bound: DAQP is not needed.
            return self._least_distance_solution(p, t0, x_u, "solved", 0, 0.0, viol, z_in, z_box)
        U = form.factor()
        if U.shape != (n, n):
            raise ValueError(f"LeastDistanceForm: U {U.shape}, expected ({n}, {n})")
        k = n_b + m
        sense = np.zeros(k, dtype=np.intc)
        # The rows DAQP gets: those violated at x_u, the hinted ones, then those the
        # subset's optimum violates (below).
        take = (lower > s.eps_abs) | (upper < -s.eps_abs)
        if s.warm_start and hint is not None:
            ids = np.asarray(hint, dtype=np.intp).reshape(-1)
            ids = ids[(ids >= 0) & (ids < 2 * (m + n))]
            up = ids >= m + n
            # Row of W of each constraint: C's row j at n_b + j, the box on x_i at its place
            # in box, -1 for a box side W does not hold.
            w_row = np.full(m + n, -1, dtype=np.intp)
            w_row[:m] = n_b + np.arange(m)
            w_row[m + box] = np.arange(n_b)
            idx = w_row[np.where(up, ids - (m + n), ids)]
            up = up[idx >= 0]
            idx = idx[idx >= 0]
            # Only a finite bound can be active.
            ok = np.where(up, np.isfinite(upper[idx]), np.isfinite(lower[idx]))
            sense[idx[ok]] = np.where(up[ok], _DAQP_ACTIVE, _DAQP_ACTIVE | _DAQP_LOWER)
            take[idx[ok]] = True
        iterations, setup = 0, 0.0
        x = np.full(n, math.nan)
        status = "max_iterations"
        for rnd in range(_SUBSET_ROUNDS):
            if rnd == _SUBSET_ROUNDS - 1:
                take[:] = True  # the last round holds every row: the full problem's optimum
            S = np.flatnonzero(take)
            W = form.rows(S)
            if W.shape != (S.shape[0], n):
                raise ValueError(f"LeastDistanceForm.rows: {W.shape}, expected ({S.shape[0]}, {n})")
            t1 = time.perf_counter()
            model = daqp.Model()
            model.settings = {"primal_tol": s.eps_abs, "iter_limit": s.max_iter}
            flag = int(model.setup(_identity(n), _zeros(n), W, upper[S], lower[S], sense[S])[0])
            setup += time.perf_counter() - t1
            if flag < 0:
                status = _DAQP_STATUS.get(flag, f"daqp_{flag}")
                break
            y, _, flag, info = model.solve()
            iterations += int(info["iterations"])
            status = _DAQP_STATUS.get(int(flag), f"daqp_{flag}")
            if status != "solved":
                break
            lam = np.asarray(info["lam"], dtype=np.float64)
            Uy = U @ y
            x = x_u + Uy
            # Every row's value at x less its value at x_u: W y, from x's rows (the rows
            # DAQP did not see are checked here, those it did are met to its tolerance).
            Wy = np.empty(k)
            Wy[:n_b] = Uy[box]
            if p.C is not None:
                Wy[n_b:] = p.C @ Uy
            out = (Wy < lower - s.eps_abs) | (Wy > upper + s.eps_abs)
            out[S] = False
            if not out.any():
                # Every row met: the subset's optimum is the full problem's (its feasible
                # set holds the full one's, and its optimum lies in it).
                z_all = np.zeros(k)
                z_all[S] = lam
                z_box[box] = z_all[:n_b]
                z_in = z_all[n_b:]
                # Its largest violation from the row values just formed (every row's value
                # at x less its value at x_u, against the bounds shifted alike), rather
                # than forming C x again.
                viol = max(
                    float((lower - Wy).max(initial=0.0)), float((Wy - upper).max(initial=0.0))
                )
                return self._least_distance_solution(
                    p, t0, x, status, iterations, setup, viol, z_in, z_box
                )
            # Next round from this one's active set, with the rows it violated.
            sense[S] = np.where(
                lam > 0.0, _DAQP_ACTIVE, np.where(lam < 0.0, _DAQP_ACTIVE | _DAQP_LOWER, 0)
            )
            take |= out
        self.reset()
        nan = np.full(n, math.nan)
        return self._least_distance_solution(
            p, t0, nan, status, iterations, setup, math.inf, z_in, z_box
        )

    def _least_distance_solution(
        self,
        p: QpProblem,
        t0: float,
        x: FloatArray,
        status: str,
        iterations: int,
        setup: float,
        violation: float,
        z_in: FloatArray,
        z_box: FloatArray,
        reused: bool = False,
    ) -> QpSolution:
        ok = status == "solved" and bool(np.isfinite(x).all())
        # A failed solve leaves no active set to warm-start from.
        self._has_result = ok
        return QpSolution(
            x=x,
            status=status if status != "solved" or ok else "non_finite",
            ok=ok,
            iterations=iterations,
            solve_time_s=time.perf_counter() - t0,
            setup_time_s=setup,
            primal_residual=violation,
            # Exact by construction: y = -W' lam is DAQP's stationarity in y, and
            # x = x_u + U y maps it to H x + g + C' z_in + z_box = 0 (up to rounding).
            dual_residual=0.0 if ok else math.inf,
            objective=p.objective(x) if ok else math.nan,
            backend=self.backend,
            reused=reused,
            active_set=False,
            y_eq=np.zeros(0),
            z_in=z_in,
            z_box=z_box,
        )


def active_constraint_ids(sol: QpSolution, rel_tol: float = 1e-9) -> npt.NDArray[np.intp]:
    """Ids (`constraint_id` numbering) of the constraints whose multiplier in
    ``sol`` is nonzero (above rel_tol times the largest): a hint for the next, similar QP."""
    z = np.concatenate([sol.z_in, sol.z_box])
    if z.shape[0] == 0 or not np.all(np.isfinite(z)):
        return np.zeros(0, dtype=np.intp)
    thresh = rel_tol * float(np.max(np.abs(z), initial=0.0))
    nz = np.flatnonzero(np.abs(z) > thresh)
    return constraint_id(sol.z_in.shape[0], sol.z_box.shape[0], nz, z[nz] > 0)


def solve_qp(
    problem: QpProblem, backend: str = "proxsuite", settings: QpSettings | None = None
) -> QpSolution:
    """One-shot solve with a fresh `QpSolver` (for tests and scripts; loops keep a solver)."""
    return QpSolver(backend, settings).solve(problem)


# --- lean path: small dense QPs with inequality rows only, solved every control tick -------


class LeanDenseQp:
    """Lean solver for a small dense QP ``min 1/2 x'Hx + g'x`` s.t. ``l <= C x <= u`` solved
    again and again with new data (e.g. the WBC's reduced QP, every tick).

    ``solve`` skips `QpProblem`'s validation and `QpSolver.solve`'s scaling, residual and
    complementarity checks, which cost more than the solve itself at this size, and hands
    the data straight to ``daqp.solve`` (DAQP, a dual active-set method in C; it factorises
    H and returns the unconstrained minimiser at once when it meets every bound). Every
    solve starts cold: on the 169 recorded WBC ticks (tests/data/wbc_ticks.npz) a warm start
    from the previous active set and a Python-side check of the unconstrained minimiser
    were both slower than DAQP alone. DAQP's result is exact once it stops (stationarity to
    rounding, multipliers of the right sign, bounds to ``settings.eps_abs``), hence no
    complementarity check; ``settings.max_iter`` caps its iterations.

    Statuses (`QpSolver`'s daqp mapping): "solved"; "primal_infeasible"; "max_iterations";
    "numerical_error" (e.g. H not positive definite). ``iterations`` is DAQP's count.
    Bounds with ``l > u`` are reported "primal_infeasible" without a solve (DAQP itself does
    not check them). The caller guarantees the shapes (H (n, n) symmetric positive
    definite, g (n,), C (m, n), l/u (m,) with +-inf for absent bounds, all float64) and
    finite data, and decides what to do on failure (e.g. solve it through `QpSolver`). No
    array passed in is kept.
    `solve_x` returns only (x, status, iterations), for a control loop's hot path (building
    the `QpSolution` costs a few microseconds).
    """

    def __init__(self, settings: QpSettings | None = None) -> None:
        self.settings = settings if settings is not None else QpSettings()

    def reset(self) -> None:
        """Nothing to forget: every solve starts cold (kept for the solvers' interface)."""

    def solve(
        self, H: FloatArray, g: FloatArray, C: FloatArray, l: FloatArray, u: FloatArray
    ) -> QpSolution:
        """Solve; never raises on solver failure (check ``ok``/``status``)."""
        t0 = time.perf_counter()
        x, status, iterations, lam = self._run(H, g, C, l, u)
        ok = status == "solved"
        m, n = C.shape[0], g.shape[0]
        z_in = lam if ok else np.zeros(m)
        if ok:
            Cx = C.dot(x)
            violation = max(float((l - Cx).max(initial=0.0)), float((Cx - u).max(initial=0.0)))
            stat = H.dot(x) + g + C.T.dot(z_in)
            dual = float(np.max(np.abs(stat), initial=0.0))
        else:
            violation = dual = math.inf
        return QpSolution(
            x=x,
            status=status,
            ok=ok,
            iterations=iterations,
            solve_time_s=time.perf_counter() - t0,
            setup_time_s=0.0,
            primal_residual=violation,
            dual_residual=dual,
            objective=float(0.5 * x.dot(H.dot(x)) + g.dot(x)) if ok else math.nan,
            backend="daqp",
            reused=False,
            active_set=True,
            y_eq=np.zeros(0),
            z_in=z_in,
            z_box=np.zeros(n),
        )

    def solve_x(
        self,
        H: FloatArray,
        g: FloatArray,
        C: FloatArray,
        l: FloatArray,
        u: FloatArray,
        x_unconstrained: FloatArray | None = None,
    ) -> tuple[FloatArray, str, int]:
        """`solve` for a control loop's hot path: (x, status, iterations) only, without
        building a `QpSolution` (multipliers, objective, timings).

        ``x_unconstrained``: the caller's -H^-1 g when its structure gives it cheaply (the
        WBC's build factors H anyway). When it meets every row to ``settings.eps_abs`` it is
        the solution (what DAQP returns at once from a cold start, since its first iterate is
        that minimiser) and DAQP is not called: 0 iterations."""
        if x_unconstrained is not None and _meets_rows(
            C, x_unconstrained, l, u, self.settings.eps_abs
        ):
            return x_unconstrained, "solved", 0
        x, status, iterations, _ = self._run(H, g, C, l, u)
        return x, status, iterations

    def _run(
        self, H: FloatArray, g: FloatArray, C: FloatArray, l: FloatArray, u: FloatArray
    ) -> tuple[FloatArray, str, int, FloatArray]:
        """x, status, iterations and DAQP's multipliers of C's rows (z_in's convention;
        meaningless unless solved)."""
        s = self.settings
        if np.greater(l, u).any():
            # DAQP does not check l <= u: with an inverted row it can report "solved".
            return np.full(g.shape[0], math.nan), "primal_infeasible", 0, np.zeros(C.shape[0])
        # A fresh sense array (all rows inactive, inequalities): a cold start.
        sense = np.zeros(C.shape[0], dtype=np.intc)
        x, _, flag, info = daqp.solve(
            H, g, C, u, l, sense, primal_tol=s.eps_abs, iter_limit=s.max_iter
        )
        status = _DAQP_STATUS.get(int(flag), f"daqp_{flag}")
        return x, status, int(info["iterations"]), info["lam"]


@numba.njit(cache=True)
def _meets_rows(C: FloatArray, x: FloatArray, l: FloatArray, u: FloatArray, eps: float) -> bool:
    """l - eps <= C x <= u + eps on every row, and l <= u (compiled: the numpy form of this
    test cost more than the WBC's whole QP build)."""
    m, n = C.shape
    for i in range(m):
        if l[i] > u[i]:
            return False
        v = 0.0
        for j in range(n):
            v += C[i, j] * x[j]
        if v < l[i] - eps or v > u[i] + eps:
            return False
    return True


def warm_up() -> None:
    """Compile (or load from the cache) `LeanDenseQp`'s compiled check for the argument types
    of a control loop, so that no control tick pays for it."""
    _meets_rows(np.zeros((1, 1)), np.zeros(1), np.zeros(1), np.zeros(1), 0.0)
