"""Tests of locoplan.sim.loop's per-tick bookkeeping kernel against the numpy expressions it
replaces (exact: the record's peaks and the commanded ratio must not change by a bit)."""

from __future__ import annotations

import numpy as np

from locoplan.sim.loop import _tick_checks


def _reference(
    tau: np.ndarray,
    limits: np.ndarray,
    applied: np.ndarray,
    peak: np.ndarray,
    peak_t: np.ndarray,
    t: float,
    qpos: np.ndarray,
    qvel: np.ndarray,
    ratio_before: float,
) -> tuple[float, bool]:
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = max(ratio_before, float(np.max(np.abs(tau) / limits)))
    a = np.abs(applied)
    bigger = a > peak
    peak[bigger] = a[bigger]
    peak_t[bigger] = t
    return ratio, bool(np.all(np.isfinite(qpos)) and np.all(np.isfinite(qvel)))


def test_tick_checks_match_numpy() -> None:
    rng = np.random.default_rng(2)
    limits = rng.uniform(5.0, 40.0, size=16)
    peak_a, peak_b = np.zeros(16), np.zeros(16)
    time_a, time_b = np.zeros(16), np.zeros(16)
    ratio_a = ratio_b = 0.0
    for k in range(500):
        tau = rng.normal(size=16) * 20.0
        applied = np.clip(tau, -limits, limits)
        qpos, qvel = rng.normal(size=23), rng.normal(size=22)
        if k % 50 == 7:
            tau[3] = np.nan  # a NaN command never raises the peak ratio
        if k % 50 == 9:
            qvel[5] = np.inf
        if k % 50 == 11:
            applied[2] = np.nan
        t = k * 2e-3
        ratio, finite = _tick_checks(tau, limits, applied, peak_a, time_a, t, qpos, qvel)
        ratio_a = max(ratio_a, ratio)
        ratio_b, finite_b = _reference(tau, limits, applied, peak_b, time_b, t, qpos, qvel, ratio_b)
        assert ratio_a == ratio_b and finite == finite_b
        assert np.array_equal(peak_a, peak_b) and np.array_equal(time_a, time_b)
    # Strided views (any layout is accepted) and a zero limit (inf, no exception).
    tau = np.arange(10.0)[::2]
    ratio, finite = _tick_checks(
        tau, np.array([1.0, 0.0, 1.0, 1.0, 1.0]), tau, np.zeros(5), np.zeros(5), 0.0, tau, tau
    )
    assert ratio == np.inf and finite
