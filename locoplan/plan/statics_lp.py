"""The two linear programmes of the static analysis (`locoplan.plan.statics`), as pure
functions of one posture's statics terms.

Unknowns: the contact forces f (3k,) of k foot points (world frame, on the robot), each with
fz >= 0 inside the friction pyramid |fx|, |fy| <= mu fz. In pinocchio's free-flyer basis,
static equilibrium with m kg at the hands is g(q) = S' tau + Jc' f + m u, where `u` (nv,) =
sum_h J_h' w_h is the generalized force of 1 kg's weight (w_h downward, split over the hands;
`StaticTerms.load_per_kg`): the base rows (first 6) of g - m u - Jc' f are zero and the rest
is tau. Solved with scipy's HiGHS (`linprog`), whose vertex solutions meet
the equalities to about 1e-9 relative.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import linprog

FloatArray = NDArray[np.float64]


class ContactForces(NamedTuple):
    """A solution: the worst torque ratio, the contact forces (3k,) N and the joint torques
    (n_joints,) N m."""

    ratio: float
    f: FloatArray
    tau: FloatArray


def _friction_rows(n_points: int, n_var: int, mu: float) -> FloatArray:
    """|fx| <= mu fz and |fy| <= mu fz of every point as rows A x <= 0 (4 per point)."""
    rows = np.zeros((4 * n_points, n_var))
    for k in range(n_points):
        for a, (axis, sign) in enumerate(((0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0))):
            rows[4 * k + a, 3 * k + axis] = sign
            rows[4 * k + a, 3 * k + 2] = -mu
    return rows


def _force_bounds(n_points: int) -> list[tuple[float | None, float | None]]:
    """Bounds of the variables: fx, fy free, fz >= 0 per point, then the last one >= 0."""
    free: tuple[float | None, float | None] = (None, None)
    up: tuple[float | None, float | None] = (0.0, None)
    return [free, free, up] * n_points + [up]


def min_worst_ratio(
    g: FloatArray,
    J_contacts: FloatArray,
    load_per_kg: FloatArray,
    mass: float,
    torque_limits: FloatArray,
    mu: float,
) -> ContactForces | None:
    """The contact forces minimising max_i |tau_i| / torque_limits_i with `mass` kg at the
    hands (variables f and the ratio t: min t, |tau(f)| <= t limits); None when no forces
    balance the robot. `g` (nv,), `J_contacts` (3k, nv), `load_per_kg` (nv,)."""
    n_points = J_contacts.shape[0] // 3
    nf = 3 * n_points
    b = g - mass * load_per_kg  # the full generalized force is b - Jc' f
    A = J_contacts.T
    c = np.zeros(nf + 1)
    c[-1] = 1.0
    lim = torque_limits[:, None]
    A_ub = np.vstack(
        (
            np.hstack((-A[6:], -lim)),  # tau <= t lim
            np.hstack((A[6:], -lim)),  # -tau <= t lim
            _friction_rows(n_points, nf + 1, mu),
        )
    )
    b_ub = np.concatenate((-b[6:], b[6:], np.zeros(4 * n_points)))
    A_eq = np.hstack((A[:6], np.zeros((6, 1))))
    res = linprog(
        c,
        A_ub=A_ub,
        b_ub=b_ub,
        A_eq=A_eq,
        b_eq=b[:6],
        bounds=_force_bounds(n_points),
        method="highs",
    )
    if res.status != 0:
        return None
    f = np.asarray(res.x[:nf])
    tau = (b - A @ f)[6:]
    return ContactForces(float(np.max(np.abs(tau) / torque_limits)), f, tau)


def max_payload(
    g: FloatArray,
    J_contacts: FloatArray,
    load_per_kg: FloatArray,
    torque_limits: FloatArray,
    mu: float,
) -> float:
    """The largest mass (kg) at the hands for which some contact forces balance the robot
    with every |tau_i| <= torque_limits_i (variables f and the mass m: max m); 0 when none
    does, not even m = 0; inf when nothing bounds it."""
    n_points = J_contacts.shape[0] // 3
    nf = 3 * n_points
    A = J_contacts.T
    u = load_per_kg[:, None]
    c = np.zeros(nf + 1)
    c[-1] = -1.0
    A_ub = np.vstack(
        (
            np.hstack((-A[6:], -u[6:])),  # tau = g - m u - A f <= lim
            np.hstack((A[6:], u[6:])),  # -tau <= lim
            _friction_rows(n_points, nf + 1, mu),
        )
    )
    b_ub = np.concatenate((torque_limits - g[6:], torque_limits + g[6:], np.zeros(4 * n_points)))
    A_eq = np.hstack((A[:6], u[:6]))
    res = linprog(
        c,
        A_ub=A_ub,
        b_ub=b_ub,
        A_eq=A_eq,
        b_eq=g[:6],
        bounds=_force_bounds(n_points),
        method="highs",
    )
    if res.status == 3:  # unbounded
        return math.inf
    return float(res.x[-1]) if res.status == 0 else 0.0
