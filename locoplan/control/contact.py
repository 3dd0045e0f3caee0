"""Line-foot contact wrench: parametrisation and its constraints (shared by MPC and WBC).

A stance foot's wrench is parametrised as w5 = [Fx', Fy', Fz, My', Mz'] in the foot's yaw
frame (x' along the foot, z up), with no moment about the foot's long axis (the paper's
selection L = [0 0; 1 0; 0 1]). In the world: F = R_z(psi) [Fx', Fy', Fz],
M = R_z(psi) [0, My', Mz'], the moment taken about the sole point under the ankle.

Centre of pressure: a vertical force Fz acting at x_cop along the foot gives the moment
My' = -x_cop Fz about the sole point, so x_cop in [-heel, toe] is -toe Fz <= My' <= heel Fz.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


# HECTOR's bound on a stance foot's normal force and the mass it was set for (N, kg): 250 N
# is 1.5 of its 17 kg weight, i.e. single support with 0.5 g of vertical acceleration or load
# to spare. Another robot gets the same multiple of its own weight (`foot_force_max`).
F_MAX_REFERENCE = 250.0  # N
F_MAX_REFERENCE_MASS = 17.0  # kg


def foot_force_max(mass: float) -> float:
    """The normal-force bound per stance foot (N) for a robot of `mass` (kg): HECTOR's 250 N
    scaled by the mass ratio (1.5 of the weight). Rounded to 1 mN, far below what the QPs
    resolve, so that a sum of decimal link masses (HECTOR's 17 kg comes out 4e-15 kg over)
    gives HECTOR's 250 N exactly. H1 (51.437 kg): 756.4 N."""
    if not (mass > 0.0 and math.isfinite(mass)):
        raise ValueError(f"mass must be a positive number of kg, got {mass}")
    return round(F_MAX_REFERENCE * mass / F_MAX_REFERENCE_MASS, 3)


# HECTOR's torsion bound and the foot length (toe + heel) it was set for (m): |Mz'| <= 0.02 Fz
# on a 0.15 m line foot. Another robot gets the same share of its foot's length
# (`torsion_bound`).
MU_TORSION_REFERENCE = 0.02  # m
FOOT_LENGTH_REFERENCE = 0.15  # m


def reference_ratio(value: float, reference: float) -> float:
    """value / reference rounded to 1e-9: a robot's figure over HECTOR's, so that HECTOR's
    own (a sum of decimal link masses comes out 4e-15 kg over 17 kg) gives exactly 1 and the
    scaled figures are HECTOR's to the bit."""
    return round(value / reference, 9)


def torsion_bound(toe: float, heel: float) -> float:
    """The torsion bound mu_t (m; |Mz'| <= mu_t Fz) of a line foot reaching `toe` ahead of
    and `heel` behind its sole site (m): HECTOR's 0.02 m times the foot length over its
    0.15 m (`reference_ratio`: HECTOR's 0.09 + 0.06 gives 0.02 exactly).

    Why it scales: the yaw moment a line foot holds by friction grows with the distance
    between its contact points (`yaw_friction_rows`: mu L Fz / 2 at most). Measured on H1
    (foot 0.175 m: 0.0233 m) on its closed-loop scripts against 0.02: in the walk square's
    first turn the trunk fell 4 deg behind its yaw reference in single support and, catching
    up with the yaw moment 0.02 allowed, a stance foot pivoted ~9 deg and took the right hip
    yaw 1.0 deg past its +-24.6 deg range for 0.13 s (25.6 deg); with 0.0233 the hip yaw
    peaks at 23.1 deg, within its range, and the other scripts track as before or 1-5 mm
    closer."""
    return MU_TORSION_REFERENCE * reference_ratio(toe + heel, FOOT_LENGTH_REFERENCE)


@dataclass(frozen=True, slots=True)
class ContactLimits:
    """Friction coefficient, vertical force bounds (N), foot lengths ahead/behind the ankle (m),
    torsional friction coefficient (m; |Mz'| <= mu_torsion Fz)."""

    mu: float = 0.5
    f_min: float = 10.0
    f_max: float = 250.0
    toe: float = 0.09
    heel: float = 0.06
    mu_torsion: float = MU_TORSION_REFERENCE
    # The centre-of-pressure dependent yaw friction rows (`yaw_friction_rows`); False gives
    # the QP as it was before them (the recorded-solution tests).
    yaw_friction: bool = True

    def __post_init__(self) -> None:
        # f_min > f_max is allowed on purpose: the QPs become infeasible and the run reports a
        # solver failure (exit 3), which is how tests force one.
        if not (self.mu > 0 and self.f_min >= 0 and self.toe > 0 and self.heel > 0):
            raise ValueError(f"inconsistent contact limits: {self}")


def wrench_rows(limits: ContactLimits) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Rows (9, 5) with bounds lo <= C w5 <= hi: friction pyramid (4), f_min <= Fz <= f_max
    (1), centre of pressure (2), torsional friction (2). Returns (C, lo, hi)."""
    mu, tz = limits.mu, limits.mu_torsion
    inf = np.inf
    C = np.array(
        [
            [1.0, 0.0, -mu, 0.0, 0.0],  # Fx' <= mu Fz
            [-1.0, 0.0, -mu, 0.0, 0.0],  # -Fx' <= mu Fz
            [0.0, 1.0, -mu, 0.0, 0.0],
            [0.0, -1.0, -mu, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0, 0.0],  # f_min <= Fz <= f_max
            [0.0, 0.0, limits.toe, 1.0, 0.0],  # My' >= -toe Fz
            [0.0, 0.0, -limits.heel, 1.0, 0.0],  # My' <= heel Fz
            [0.0, 0.0, -tz, 0.0, 1.0],  # Mz' <= mu_t Fz
            [0.0, 0.0, tz, 0.0, 1.0],  # Mz' >= -mu_t Fz
        ]
    )
    lo = np.array([-inf, -inf, -inf, -inf, limits.f_min, 0.0, -inf, -inf, 0.0])
    hi = np.array([0.0, 0.0, 0.0, 0.0, limits.f_max, inf, 0.0, 0.0, inf])
    if limits.yaw_friction:
        C_yaw, lo_yaw, hi_yaw = yaw_friction_rows(mu, limits.toe, limits.heel)
        C = np.vstack([C, C_yaw])
        lo, hi = np.concatenate([lo, lo_yaw]), np.concatenate([hi, hi_yaw])
    return C, lo, hi


def yaw_friction_rows(
    mu: float, toe: float, heel: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Rows (4, 5) on w5 = [Fx', Fy', Fz, My', Mz'] and their bounds lo, hi (each row <= 0):
    the yaw moment a line foot can hold by friction depends on where its centre of pressure is.

    A line foot touches the ground at its toe (x = toe) and heel (x = -heel) points (the
    MJCF's sole spheres, `condim` 3: a point contact holds no moment about the normal). With
    the CoP at x, the normal force splits f_toe = (heel Fz - My') / L and f_heel = (toe Fz +
    My') / L (L = toe + heel, My' = -x Fz), and a yaw moment needs opposite sideways forces at
    the two points: |Mz'| <= mu L min(f_toe, f_heel), i.e. |Mz'| <= mu (toe Fz + My') and
    |Mz'| <= mu (heel Fz - My'). Near the middle this allows mu L Fz / 2 (0.0375 Fz for
    HECTOR, looser than the torsion bound mu_t Fz = 0.02 Fz, which stays); with the CoP at the
    toe or the heel it allows nothing, and a stance foot asked for yaw there pivots about that
    point (seen: pick-walk-drop's stance feet turned 25-35 deg in single support, the hip yaw
    at its 30 deg limit, while the CoP sat near the toe under the carried box)."""
    rows = np.array(
        [
            [0.0, 0.0, -mu * toe, -mu, 1.0],  # Mz' - mu (toe Fz + My') <= 0
            [0.0, 0.0, -mu * toe, -mu, -1.0],  # -Mz' - mu (toe Fz + My') <= 0
            [0.0, 0.0, -mu * heel, mu, 1.0],  # Mz' - mu (heel Fz - My') <= 0
            [0.0, 0.0, -mu * heel, mu, -1.0],  # -Mz' - mu (heel Fz - My') <= 0
        ]
    )
    return rows, np.full(4, -np.inf), np.zeros(4)


def wrench5_to_world(yaw: float) -> FloatArray:
    """Matrix (6, 5) mapping w5 (foot yaw frame) to the world wrench [F; M] at the sole."""
    c, s = np.cos(yaw), np.sin(yaw)
    Rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    T = np.zeros((6, 5))
    T[0:3, 0:3] = Rz
    T[3:6, 3:5] = Rz[:, 1:3]
    return T


def ankle_torque_row(axis_foot: FloatArray, r_sole_from_ankle_foot: FloatArray) -> FloatArray:
    """Row (5,) on w5 = [Fx', Fy', Fz, My', Mz'] giving the moment of a stance foot's contact
    wrench about its ankle axis (N m): with the unit axis `axis_foot` (3,) and the sole point
    relative to a point of the axis `r_sole_from_ankle_foot` (3,) (m), both in the foot's yaw
    frame, a . (M + r x F) = F . (a x r) + a . M, M = (0, My', Mz'). The ankle joint holds its
    negative (less the foot's own weight and inertia). Flat foot, axis y, sole d below the
    axis: [-d, 0, 0, 1, 0], i.e. My' - d Fx'."""
    a = np.asarray(axis_foot, dtype=float)
    axr = np.cross(a, np.asarray(r_sole_from_ankle_foot, dtype=float))
    return np.array([axr[0], axr[1], axr[2], a[1], a[2]])


def ankle_row_binds(row: FloatArray, limits: ContactLimits, torque: float) -> bool:
    """Whether a foot wrench the other rows allow (`wrench_rows`: friction, f_max, the CoP
    within toe and heel, the torsion bound) can need more than `torque` (N m) about the ankle
    (`row` from `ankle_torque_row`): an upper bound of |row . w5| over that set,
    f_max (mu (|r0| + |r1|) + |r2| + |r3| max(toe, heel) + |r4| mu_t), against `torque`.

    HECTOR: 250 N (0.5 x 0.04 + 0.09) = 27.5 N m < 33.5 N m, its foot never asks its ankle
    for more than it has. H1: 756.4 N (0.5 x 0.07 + 0.14) = 132 N m > 40 N m: a CoP within
    the foot's 0.14 m toe asks the ankle three times its limit in single support."""
    r = np.abs(np.asarray(row, dtype=float))
    bound = limits.f_max * (
        limits.mu * (r[0] + r[1])
        + r[2]
        + r[3] * max(limits.toe, limits.heel)
        + r[4] * limits.mu_torsion
    )
    return bool(bound > torque)
