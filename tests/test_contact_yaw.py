"""The yaw friction a line foot can hold depends on its centre of pressure
(`locoplan.control.contact.yaw_friction_rows`): checked on the analytic two-point model."""

from __future__ import annotations

import numpy as np

from locoplan.control.contact import ContactLimits, wrench_rows


def _allowed_yaw(x_cop: float, fz: float, limits: ContactLimits) -> float:
    """Largest |Mz'| that the rows of `wrench_rows` accept for a vertical force fz (N) at x_cop
    (m ahead of the sole site), found by bisection on Mz' (to 1e-9 N m)."""
    C, lo, hi = wrench_rows(limits)

    def ok(mz: float) -> bool:
        w = np.array([0.0, 0.0, fz, -x_cop * fz, mz])
        v = C @ w
        return bool(np.all(v >= lo - 1e-12) and np.all(v <= hi + 1e-12))

    a, b = 0.0, 10.0 * fz
    if not ok(0.0):
        return -1.0
    for _ in range(100):
        m = 0.5 * (a + b)
        a, b = (m, b) if ok(m) else (a, m)
    return a


def test_yaw_friction_vanishes_at_the_toe_and_heel_and_follows_the_two_point_split() -> None:
    """Two contact points, toe (x = t) and heel (x = -h), friction mu: with the CoP at x the
    normal force splits f_toe = Fz (x + h) / L, f_heel = Fz (t - x) / L, and opposite sideways
    forces at the points hold |Mz'| <= mu L min(f_toe, f_heel). Without the torsion cap
    (mu_torsion large) the rows reproduce that to 1e-6 N m; with it they never allow more than
    mu_t Fz; at either end of the foot nothing."""
    fz = 150.0
    loose = ContactLimits(mu_torsion=1.0)
    t, h, mu = loose.toe, loose.heel, loose.mu
    for x in np.linspace(-h, t, 13):
        expected = mu * (t + h) * min(fz * (x + h), fz * (t - x)) / (t + h)
        assert abs(_allowed_yaw(float(x), fz, loose) - expected) < 1e-6, x
    capped = ContactLimits()
    for x in np.linspace(-h, t, 13):
        assert _allowed_yaw(float(x), fz, capped) <= capped.mu_torsion * fz + 1e-6
    assert _allowed_yaw(t, fz, capped) < 1e-6
    assert _allowed_yaw(-h, fz, capped) < 1e-6
    # Without the rows, the cap alone holds at the toe: the QP of before.
    assert abs(_allowed_yaw(t, fz, ContactLimits(yaw_friction=False)) - 0.02 * fz) < 1e-6
