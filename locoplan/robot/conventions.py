"""Free-flyer state conventions: MuJoCo <-> pinocchio (pure numpy).

Both models put the free joint first, then the same 16 hinges in the same order, so only
the 7 + 6 floating-base coordinates differ:

| | MuJoCo `qpos` / `qvel` | pinocchio `q` / `v` |
|---|---|---|
| position | p_base_world (3) | p_base_world (3) |
| orientation | quaternion (w, x, y, z) | quaternion (x, y, z, w) |
| linear velocity | of the base origin, **world** axes | of the base origin, **base** axes |
| angular velocity | base axes | base axes |

With R = R_base_to_world and T(q) = blkdiag(R^T, I3, I_nj) (shape nv x nv), v_pin = T v_mj.
T is orthogonal, so T^-1 = T^T. Power is invariant (tau_mj^T v_mj = tau_pin^T v_pin), hence

- generalized forces: tau_mj = T^T tau_pin;
- Jacobians: J_mj = J_pin T (same task-space velocity from either velocity vector);
- mass matrix: M_mj = T^T M_pin T;
- accelerations: a_pin = T a_mj + c with c = [-omega x v_base_local; 0; 0] because R^T
  rotates with the base (d/dt R^T = -[omega]x R^T, omega in base axes);
- bias forces: qfrc_bias_mj = T^T (nle_pin + M_pin c).

All functions take single states (1-D arrays); nq = 7 + nj, nv = 6 + nj.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

_WXYZ_TO_XYZW = np.array([1, 2, 3, 0])
_XYZW_TO_WXYZ = np.array([3, 0, 1, 2])


def quat_wxyz_to_rotation(quat_wxyz: FloatArray) -> FloatArray:
    """Rotation matrix (3, 3) of a quaternion (w, x, y, z); normalised first."""
    quat = np.asarray(quat_wxyz, dtype=np.float64)
    # Scalar arithmetic on Python floats: 2-3x cheaper than on numpy scalars, and the same
    # IEEE operations, so the matrix is bit for bit what the numpy expressions gave. The norm
    # stays numpy's (its dot product's summation order is BLAS's).
    w, x, y, z = (quat / _norm(quat)).tolist()
    return _rotation(w, x, y, z)


def _norm(quat: FloatArray) -> float:
    """Euclidean norm of a 1-D float64 array: what `np.linalg.norm` computes for one (the
    square root of `dot`, the same bits), without its dispatch."""
    return math.sqrt(quat.dot(quat))


def _rotation(w: float, x: float, y: float, z: float) -> FloatArray:
    """Rotation matrix (3, 3) of the unit quaternion (w, x, y, z)."""
    return np.array(
        [
            1 - 2 * (y * y + z * z),
            2 * (x * y - w * z),
            2 * (x * z + w * y),
            2 * (x * y + w * z),
            1 - 2 * (x * x + z * z),
            2 * (y * z - w * x),
            2 * (x * z - w * y),
            2 * (y * z + w * x),
            1 - 2 * (x * x + y * y),
        ]
    ).reshape(3, 3)


def mj_base_rotation(qpos: FloatArray) -> FloatArray:
    """R_base_to_world (3, 3) from a MuJoCo qpos."""
    return quat_wxyz_to_rotation(qpos[3:7])


def pin_base_rotation(q: FloatArray) -> FloatArray:
    """R_base_to_world (3, 3) from a pinocchio q."""
    quat = np.asarray(q[3:7], dtype=np.float64)
    # The norm of (x, y, z, w) in this order is the norm of (w, x, y, z) of earlier versions
    # only up to round-off, so reorder first (bit-for-bit the same matrix as before).
    wxyz = quat[_XYZW_TO_WXYZ]
    w, x, y, z = (wxyz / _norm(wxyz)).tolist()
    return _rotation(w, x, y, z)


def mj_to_pin_q(qpos: FloatArray) -> FloatArray:
    """pinocchio q (nq,) from MuJoCo qpos (nq,): quaternion reordered and normalised."""
    q = np.array(qpos, dtype=np.float64)
    quat = q[3:7] / np.linalg.norm(q[3:7])
    q[3:7] = quat[_WXYZ_TO_XYZW]
    return q


def mj_to_pin_state(qpos: FloatArray, qvel: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(`mj_to_pin_q(qpos)`, `mj_to_pin_v(qpos, qvel)`) with one normalisation and one
    rotation matrix: the same numbers as the two calls (the same IEEE operations: numpy's
    norm, element-wise division by it on Python floats, the matrix product), for less than
    half their cost."""
    q = np.array(qpos, dtype=np.float64)
    n = _norm(q[3:7])
    w, x, y, z = q[3:7].tolist()
    w, x, y, z = w / n, x / n, y / n, z / n
    q[3:7] = (x, y, z, w)
    v = np.array(qvel, dtype=np.float64)
    v[0:3] = _rotation(w, x, y, z).T @ v[0:3]
    return q, v


def pin_to_mj_q(q: FloatArray) -> FloatArray:
    """MuJoCo qpos (nq,) from pinocchio q (nq,): quaternion reordered to (w, x, y, z)."""
    qpos = np.array(q, dtype=np.float64)
    qpos[3], qpos[4:7] = q[6], q[3:6]
    return qpos


def mj_to_pin_v(qpos: FloatArray, qvel: FloatArray) -> FloatArray:
    """pinocchio v (nv,) = T qvel: the base linear velocity rotated into the base frame."""
    v = np.array(qvel, dtype=np.float64)
    v[0:3] = mj_base_rotation(qpos).T @ qvel[0:3]
    return v


def pin_to_mj_v(q: FloatArray, v: FloatArray) -> FloatArray:
    """MuJoCo qvel (nv,) = T^T v: the base linear velocity rotated into the world frame."""
    qvel = np.array(v, dtype=np.float64)
    qvel[0:3] = pin_base_rotation(q) @ v[0:3]
    return qvel


def velocity_transform(R_base_to_world: FloatArray, nv: int) -> FloatArray:
    """T (nv, nv) with v_pin = T v_mj: blkdiag(R^T, I3, I_{nv-6})."""
    T = np.eye(nv)
    T[0:3, 0:3] = R_base_to_world.T
    return T


def basis_change_drift(v: FloatArray) -> FloatArray:
    """c (nv,) in a_pin = T a_mj + c: [-omega x v_base_local; 0], from pinocchio v."""
    c = np.zeros_like(v, dtype=np.float64)
    c[0:3] = -np.cross(v[3:6], v[0:3])
    return c


def pin_to_mj_mass_matrix(q: FloatArray, M_pin: FloatArray) -> FloatArray:
    """MuJoCo-convention mass matrix (nv, nv): T^T M_pin T."""
    T = velocity_transform(pin_base_rotation(q), M_pin.shape[0])
    return T.T @ M_pin @ T


def pin_to_mj_bias(q: FloatArray, v: FloatArray, M_pin: FloatArray, nle: FloatArray) -> FloatArray:
    """MuJoCo qfrc_bias (nv,) from pinocchio's nle = C v + g: T^T (nle + M_pin c)."""
    T = velocity_transform(pin_base_rotation(q), M_pin.shape[0])
    return T.T @ (nle + M_pin @ basis_change_drift(v))


def pin_to_mj_force(q: FloatArray, tau_pin: FloatArray) -> FloatArray:
    """Generalized force (nv,) in MuJoCo convention: T^T tau_pin."""
    f = np.array(tau_pin, dtype=np.float64)
    f[0:3] = pin_base_rotation(q) @ tau_pin[0:3]
    return f


def mj_to_pin_force(qpos: FloatArray, tau_mj: FloatArray) -> FloatArray:
    """Generalized force (nv,) in pinocchio convention: T tau_mj."""
    f = np.array(tau_mj, dtype=np.float64)
    f[0:3] = mj_base_rotation(qpos).T @ tau_mj[0:3]
    return f


def pin_to_mj_jacobian(q: FloatArray, J_pin: FloatArray) -> FloatArray:
    """Jacobian (m, nv) acting on MuJoCo qvel: J_pin T."""
    J = np.array(J_pin, dtype=np.float64)
    J[:, 0:3] = J_pin[:, 0:3] @ pin_base_rotation(q).T
    return J


def mj_to_pin_a(qpos: FloatArray, qvel: FloatArray, qacc: FloatArray) -> FloatArray:
    """pinocchio a (nv,) = T qacc + c from MuJoCo qpos, qvel, qacc."""
    a = mj_to_pin_v(qpos, qacc)
    return a + basis_change_drift(mj_to_pin_v(qpos, qvel))


def pin_to_mj_a(q: FloatArray, v: FloatArray, a: FloatArray) -> FloatArray:
    """MuJoCo qacc (nv,) = T^T (a - c) from pinocchio q, v, a."""
    return pin_to_mj_v(q, a - basis_change_drift(v))
