"""Compiled pieces of the controller's per-update reference pipeline (numba, `cache=True`).

Why compiled: around each MPC update the controller shapes the plan's reference (the held
load's CoM shift, `LocoManipulationController._com_shift`), a few dozen numpy calls on arrays
of some 40 rows. Each such call costs 1-3 us alone but 3-5 times that inside the closed loop,
where MuJoCo and pinocchio run between them and the caches are cold (package transfer,
2026-12-08: the shift's arithmetic took 55-60 us of its 205 us per update). Each formula is
written as the numpy it replaces, operation for operation in the same order (no fast-math:
no reassociation, no fused multiply-add), so the results are the same to the bit
(tests/test_controller_load.py checks them against that numpy).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from numba import njit

FloatArray = npt.NDArray[np.float64]


@njit(cache=True)
def load_shift(
    both: FloatArray, p_com: FloatArray, mass: FloatArray, robot_mass: float
) -> tuple[FloatArray, FloatArray]:
    """The held load's CoM shift s = m_o d / (m + m_o) (`_com_shift`) as its size (n,) and
    unit direction (n, 2) (zero where the size is under 1e-9 m): ``both`` (2n, >= 2) the
    object's planned positions at the lead times and at the times concerned, ``p_com``
    (n, >= 2) the CoM reference, ``mass`` (n,) the load there; d is whichever of the two
    object offsets from the CoM is the farther (the lead time's on a tie)."""
    n = mass.shape[0]
    size = np.empty(n)
    unit = np.empty((n, 2))
    for k in range(n):
        dx = both[k, 0] - p_com[k, 0]
        dy = both[k, 1] - p_com[k, 1]
        nx = both[n + k, 0] - p_com[k, 0]
        ny = both[n + k, 1] - p_com[k, 1]
        if nx * nx + ny * ny > dx * dx + dy * dy:
            dx, dy = nx, ny
        r = mass[k] / (robot_mass + mass[k])
        sx = r * dx
        sy = r * dy
        sz = math.sqrt(sx * sx + sy * sy)
        size[k] = sz
        if sz > 1e-9:
            unit[k, 0] = sx / sz
            unit[k, 1] = sy / sz
        else:
            unit[k, 0] = 0.0
            unit[k, 1] = 0.0
    return size, unit


@njit(cache=True)
def larger_shift(along: FloatArray, unit: FloatArray, pre: FloatArray) -> FloatArray:
    """Per row, the larger of the shift -along unit (n,) x (n, 2) and ``pre`` (n, 2) (the
    pre-lift lean; the shift on a tie)."""
    n = along.shape[0]
    out = np.empty((n, 2))
    for k in range(n):
        sx = -along[k] * unit[k, 0]
        sy = -along[k] * unit[k, 1]
        if pre[k, 0] * pre[k, 0] + pre[k, 1] * pre[k, 1] > sx * sx + sy * sy:
            out[k, 0] = pre[k, 0]
            out[k, 1] = pre[k, 1]
        else:
            out[k, 0] = sx
            out[k, 1] = sy
    return out


def warm_up() -> None:
    """Compile (or load from the cache) the kernels for the types the controller passes."""
    size, unit = load_shift(np.zeros((2, 2)), np.zeros((1, 3)), np.ones(1), 1.0)
    larger_shift(size, unit, np.zeros((1, 2)))
