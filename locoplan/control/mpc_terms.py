"""Structured pieces of the condensed multi-contact MPC (see `mpc`): functions on arrays.

The SRBD's A is nilpotent, so every block of the condensed prediction matrix is an affine
function of the step distance. The Hessian is therefore assembled from per-step features
Phi_k (6 x 10: the omega and pdot kicks of step k's ten foot-frame wrench components) and a
per-step-pair kernel K[k, l] (6 x 6) that depends only on the linearisation yaws:
H[k, l] = Phi_k' K[k, l] Phi_l + R. With Q diagonal there are no cross terms between the
(Theta, omega) and (p, pdot) groups:

    K_omega[k, l] = cnt Q_omega + dt^2 sum_{i >= m} (C_i - E_k)' Q_Theta (C_i - E_l)
    K_pdot[k, l]  = cnt Q_pdot  + dt^2 sum_{i >= m} (i - k + 1/2)(i - l + 1/2) Q_p

with m = max(k, l), cnt = N - m, C_i = sum_{j <= i} R_z(yaw_j)', E_k = C_k - R_z(yaw_k)'/2.
For k >= l both are a term of k plus a term of k times one of l (`mpc_kernels`), so H is one
(n x 12) (12 x n) product. The arithmetic runs in the compiled kernels of `mpc_kernels`;
these wrappers fix the dtypes and layouts the kernels are compiled for.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from locoplan.control import mpc_kernels
from locoplan.control.contact import yaw_friction_rows

if TYPE_CHECKING:
    from locoplan.control.mpc import MpcInput, MpcSettings

FloatArray = npt.NDArray[np.float64]


def _f64(a: npt.ArrayLike) -> FloatArray:
    """``a`` as a C-contiguous float64 array (no copy if it is one): the layout and dtype the
    kernels are compiled for."""
    return np.ascontiguousarray(a, dtype=np.float64)


_ZEROS: dict[int, FloatArray] = {}


def _zeros_n3(N: int) -> FloatArray:
    """A read-only (N, 3) array of zeros, shared."""
    z = _ZEROS.get(N)
    if z is None:
        z = np.zeros((N, 3))
        z.flags.writeable = False
        _ZEROS[N] = z
    return z


@dataclass(frozen=True, slots=True)
class Kernel:
    """Cached per (N, dt, Q, yaw_lin, I_body): the yaw-dependent terms (all (N, 3, 3) but
    alpha and beta (N, 3)).

    ``RzT`` R_z(yaw_k)'; ``C`` C_i = sum_{j <= i} R_z(yaw_j)'; ``E`` C_k - R_z(yaw_k)' / 2,
    so that the pitch/roll/yaw response of x_{i+1} to step k's omega kick is
    dt (C_i - E_k) (i >= k); ``Iinv`` the trunk's inverse world inertia R_z I_body^-1 R_z';
    ``P``, ``V``, ``alpha``, ``beta`` the step-pair kernel in the separable form of
    `mpc_kernels` (K[k, l] = P_k + V_k E_l and diag(alpha_k - l beta_k) for k >= l).
    """

    RzT: FloatArray
    C: FloatArray
    E: FloatArray
    Iinv: FloatArray
    P: FloatArray
    V: FloatArray
    alpha: FloatArray
    beta: FloatArray


def build_kernel(dt: float, q: FloatArray, yaw_lin: FloatArray, Ib: FloatArray) -> Kernel:
    """The `Kernel` for step ``dt`` (s), the state weights ``q`` (15,), the linearisation
    yaws ``yaw_lin`` (N,) (rad) and the body inertia ``Ib`` (3, 3) (kg m^2, trunk axes)."""
    RzT, C, E, Iinv, P, V, alpha, beta = mpc_kernels.yaw_terms(
        float(dt), _f64(q), _f64(yaw_lin), _f64(Ib)
    )
    return Kernel(RzT=RzT, C=C, E=E, Iinv=Iinv, P=P, V=V, alpha=alpha, beta=beta)


@dataclass(frozen=True, slots=True)
class StepTerms:
    """Per-step quantities of one problem (all world frame).

    ``Iinv`` (N, 3, 3) inverse world inertia, ``mass`` (N,), ``tau_ext`` (N, 3) and
    ``f_ext`` (N, 3) the known external torque about the lever origin and force (zeros when
    no object is held or in the combined model), ``Tw`` (N, 2, 3, 5) the torque of a unit
    foot-frame wrench, ``cos_foot``/``sin_foot`` (N, 2) of the foot yaws, ``Phi`` (N, 6, 10)
    the omega/pdot kicks of the 10 wrench components of step k (zero columns for swing
    feet), ``cols`` the stance variable indices into the 10N layout, in the QP's order:
    steps from N-1 down to 0.
    """

    Iinv: FloatArray
    mass: FloatArray
    tau_ext: FloatArray
    f_ext: FloatArray
    Tw: FloatArray
    cos_foot: FloatArray
    sin_foot: FloatArray
    Phi: FloatArray
    cols: npt.NDArray[np.intp]


def step_terms(
    inp: MpcInput,
    dt: float,
    Iinv_model2: FloatArray,
    Ib: FloatArray,
    lever_path: FloatArray | None = None,
) -> StepTerms:
    """Per-step terms; ``Iinv_model2`` (N, 3, 3) is R_z I_body^-1 R_z^T at yaw_lin (cached).

    The lever arms of step k are taken from the CoM at step k (x0's for k = 0, x_ref[k-1]'s
    after, or ``lever_path[k-1]``'s (N, 3) when given); with a held object the combined
    model (Model 1) takes the joint CoM, mass and inertia instead, the external-force model
    (Model 2) the object's weight as a known wrench.
    """
    N = inp.horizon
    m_o = inp.object_mass
    if isinstance(m_o, np.ndarray) and m_o.shape == (N,):
        m_o = _f64(m_o)
    else:
        m_o = np.full(N, float(np.asarray(m_o)))
    p_object = _zeros_n3(N) if inp.p_object is None else _f64(inp.p_object)
    # Writable like every given a_object (a read-only array is another numba signature).
    a_object = np.zeros((N, 3)) if inp.a_object is None else _f64(inp.a_object)
    Iinv, mass, tau_ext, f_ext, Tw, c, s, Phi, cols = mpc_kernels.step_terms(
        float(dt),
        _f64(inp.x0),
        _f64(inp.x_ref[:, 3:6] if lever_path is None else lever_path),
        np.ascontiguousarray(inp.contact, dtype=np.bool_),
        _f64(inp.p_feet),
        _f64(inp.foot_yaw),
        _f64(inp.yaw_lin),
        float(inp.mass),
        _f64(Ib),
        _f64(Iinv_model2),
        np.ascontiguousarray(inp.object_held, dtype=np.bool_),
        m_o,
        p_object,
        a_object,
        inp.model == "combined",
    )
    return StepTerms(
        Iinv=Iinv,
        mass=mass,
        tau_ext=tau_ext,
        f_ext=f_ext,
        Tw=Tw,
        cos_foot=c,
        sin_foot=s,
        Phi=Phi,
        cols=cols,
    )


def propagate(
    x0: FloatArray,
    RzT: FloatArray,
    Iinv: FloatArray,
    mass: FloatArray,
    tau: FloatArray,
    force: FloatArray,
    dt: float,
) -> FloatArray:
    """Exact ZOH rollout x_1..x_N (N, 15) of the SRBD under known per-step wrenches.

    x0 (15,), RzT (N, 3, 3) = R_z(yaw_lin_k)^T, Iinv (N, 3, 3) world inverse inertia (kg^-1
    m^-2), mass (N,) (kg), tau (N, 3) the torque about the CoM (N m) and force (N, 3) the
    contact plus external force (N), both world and constant over each step. Per step, with
    a_w = dt Iinv tau and a_v = dt (force / mass + g): omega and velocity grow by a_w and a_v,
    Theta by dt R_z' (omega + a_w / 2) and the position by dt (v + a_v / 2).
    """
    return mpc_kernels.propagate(_f64(x0), RzT, Iinv, mass, tau, force, float(dt))


def wrench_rows(s: MpcSettings) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Per stance foot: rows (m, 5) and bounds lo, hi with lo <= rows w <= hi."""
    mu = s.mu
    rows = [
        [1.0, 0.0, -mu, 0.0, 0.0],  # Fx' - mu Fz <= 0
        [1.0, 0.0, mu, 0.0, 0.0],  # Fx' + mu Fz >= 0
        [0.0, 1.0, -mu, 0.0, 0.0],
        [0.0, 1.0, mu, 0.0, 0.0],
        [0.0, 0.0, s.toe, 1.0, 0.0],  # My' + toe Fz >= 0
        [0.0, 0.0, -s.heel, 1.0, 0.0],  # My' - heel Fz <= 0
    ]
    inf = np.inf
    lo = [-inf, 0.0, -inf, 0.0, 0.0, -inf]
    hi = [0.0, inf, 0.0, inf, inf, 0.0]
    if s.mu_torsion is not None:
        rows += [[0.0, 0.0, -s.mu_torsion, 0.0, 1.0], [0.0, 0.0, s.mu_torsion, 0.0, 1.0]]
        lo += [-inf, 0.0]
        hi += [0.0, inf]
        if s.yaw_friction:
            # The yaw friction a line foot has depends on its centre of pressure (contact.py).
            C_yaw, lo_yaw, hi_yaw = yaw_friction_rows(mu, s.toe, s.heel)
            rows += C_yaw.tolist()
            lo += lo_yaw.tolist()
            hi += hi_yaw.tolist()
    if s.ankle_row is not None:
        rows.append(list(s.ankle_row))
        lo.append(-s.ankle_torque)
        hi.append(s.ankle_torque)
    return np.array(rows), np.array(lo), np.array(hi)
