"""Whole-body control (locoplan.control.wbc): the prioritised projection and the WBC QP.

The fast paths are checked against the straightforward formulas: the projection against the
plain damped pseudo-inverse recursion, the reduced QP (lean path) against the full QP solved
by the generic `QpSolver` at a tight tolerance, and the torques against those the WBC gave
before the lean path, on recorded walking ticks (tests/data/wbc_ticks.npz).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from wbc_fixtures import contacts, n_ticks, recording, task_args

from locoplan.control.contact import ContactLimits, wrench5_to_world
from locoplan.control.qp import QpSettings, QpSolver
from locoplan.control.tasks import build_tasks, rot_z
from locoplan.control.wbc import (
    TASK_DAMPING,
    AccelerationTask,
    StanceContact,
    WbcSettings,
    WholeBodyQp,
    prioritized_acceleration,
)

NV = 22
RECORDED_DAMPING = 1e-6  # what the recorded ticks' task stacks were solved with


def _plain_prioritized(tasks: list[AccelerationTask], nv: int, damping: float) -> np.ndarray:
    """The textbook recursion: JN = J N, JN+ = JN' (JN JN' + d I)^-1, N -= JN+ JN."""
    qdd = np.zeros(nv)
    N = np.eye(nv)
    for t in tasks:
        JN = t.J @ N
        pinv = JN.T @ np.linalg.inv(JN @ JN.T + damping * np.eye(JN.shape[0]))
        qdd = qdd + pinv @ (t.xdd_des - t.jdot_v - t.J @ qdd)
        N = N - pinv @ JN
    return qdd


def _random_tasks(rng: np.random.Generator, sizes: list[int], nv: int) -> list[AccelerationTask]:
    return [
        AccelerationTask(rng.normal(size=(k, nv)), rng.normal(size=k), rng.normal(size=k))
        for k in sizes
    ]


def _tight_reference(tau_limits: np.ndarray, limits: ContactLimits | None = None) -> WholeBodyQp:
    """The full QP through the generic path, solved far tighter than the default 1e-6."""
    wbc = WholeBodyQp(
        tau_limits,
        WbcSettings(lean=False, limits=limits or ContactLimits(), weight_joint=0.0),
    )
    wbc._solver = QpSolver("proxsuite", QpSettings(eps_abs=1e-11, max_iter=1000))
    return wbc


# --- prioritized_acceleration -----------------------------------------------------------------


# Stacks of at most 20 rows on nv = 22: every level keeps full rank in the null space above.
@pytest.mark.parametrize("sizes", [[10, 6, 4], [5, 6, 6], [6], [3, 4], [2, 3, 4, 5], [12, 8]])
@pytest.mark.parametrize("seed", range(4))
def test_projection_equals_the_plain_recursion(sizes: list[int], seed: int) -> None:
    rng = np.random.default_rng(seed)
    tasks = _random_tasks(rng, sizes, NV)
    for damping in (1e-6, 1e-3):
        got = prioritized_acceleration(tasks, NV, damping)
        want = _plain_prioritized(tasks, NV, damping)
        # Full-rank Gaussian tasks (condition numbers ~10-100): both are backward stable,
        # 1e-9 leaves three orders of magnitude above rounding.
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-9)


def test_projection_equals_the_plain_recursion_on_recorded_ticks() -> None:
    for i in range(n_ticks()):
        tasks = build_tasks(*task_args(i))
        got = prioritized_acceleration(tasks, NV)
        want = _plain_prioritized(tasks, NV, TASK_DAMPING)
        # qdd up to ~1e3 rad/s^2 on rank-deficient stacks with damping 1e-6 (the swing level
        # in the null space of the contacts and trunk): 1e-8 relative to that scale.
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-8 * max(1.0, np.abs(want).max()))


@pytest.mark.parametrize("seed", range(6))
def test_lower_tasks_do_not_disturb_higher_ones(seed: int) -> None:
    rng = np.random.default_rng(seed)
    tasks = _random_tasks(rng, [8, 6, 4, 3], NV)
    damping = 1e-12
    prev = None
    for n in range(1, len(tasks) + 1):
        qdd = prioritized_acceleration(tasks[:n], NV, damping)
        # The task just added is met (21 <= 22 rows: all feasible together).
        t = tasks[n - 1]
        np.testing.assert_allclose(t.J @ qdd + t.jdot_v, t.xdd_des, atol=1e-8)
        if prev is not None:
            # ... and adding it left every task above where it was: J_i N_n = O(damping).
            for t in tasks[: n - 1]:
                np.testing.assert_allclose(t.J @ qdd, t.J @ prev, atol=1e-8)
        prev = qdd


@pytest.mark.parametrize(("damping", "tol"), [(1e-10, 1e-6), (1e-6, 5e-3)])
def test_priority_on_recorded_ticks(damping: float, tol: float) -> None:
    """The swing/hand level cannot all be met (it competes with the trunk and contacts); it
    must not move the contact or trunk accelerations the levels above it fixed, and the
    contacts must hold. Both only up to the damping's leak, O(damping / sigma_min^2) times
    the accelerations (sigma_min ~0.14, qdd up to ~600 rad/s^2): measured 1.2e-7 m/s^2 at
    damping 1e-10 and 1.2e-3 m/s^2 at the controller's 1e-6, linear in the damping."""
    for i in range(n_ticks()):
        tasks = build_tasks(*task_args(i))
        upper = prioritized_acceleration(tasks[:-1], NV, damping)
        full = prioritized_acceleration(tasks, NV, damping)
        contact = tasks[0]
        np.testing.assert_allclose(contact.J @ full + contact.jdot_v, 0.0, atol=tol)
        for t in tasks[:-1]:
            np.testing.assert_allclose(t.J @ full, t.J @ upper, rtol=0, atol=tol)


# --- the WBC QP ------------------------------------------------------------------------------


def _tick(i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[StanceContact], np.ndarray]:
    rec = recording()
    # The recording's ticks were made with damping 1e-6: the QP tests below check the QP.
    qdd = prioritized_acceleration(build_tasks(*task_args(i)), NV, RECORDED_DAMPING)
    return rec["M"][i], rec["h"][i], qdd, contacts(i), rec["tau_ext"][i]


def _assert_same_output(got, want, atol: float) -> None:  # type: ignore[no-untyped-def]
    np.testing.assert_allclose(got.tau, want.tau, rtol=0, atol=atol)
    np.testing.assert_allclose(got.delta_base, want.delta_base, rtol=0, atol=atol)
    for a, b in zip(got.w5, want.w5, strict=True):
        np.testing.assert_allclose(a, b, rtol=0, atol=atol)


def test_lean_qp_equals_generic_full_qp_on_recorded_ticks() -> None:
    rec = recording()
    lean = WholeBodyQp(rec["tau_limits"])
    ref = _tight_reference(rec["tau_limits"])
    n_active = 0
    for i in range(n_ticks()):
        args = _tick(i)
        got = lean.solve(*args)
        want = ref.solve(*args)
        assert got.ok and want.ok
        n_active += got.iterations > 0
        # Both optima to better than 1e-9 (active-set bounds 1e-9, proxsuite eps 1e-11);
        # 1e-6 N, N m, m/s^2 is what the task asks and far below what matters physically.
        _assert_same_output(got, want, 1e-6)
    assert n_active > 10  # contact rows (Fz >= f_min, CoP, yaw friction) bind at times


def test_torques_equal_the_recorded_ones() -> None:
    """End to end (tasks, projection, QP) against what the WBC returned before the lean path:
    that one solved with proxsuite at eps_abs 1e-6, so its torques are within ~1e-6 N m of
    the optimum (9e-7 measured on 3000 ticks)."""
    rec = recording()
    # Recorded before the centre-of-pressure dependent yaw friction rows: the same QP.
    wbc = WholeBodyQp(rec["tau_limits"], WbcSettings(limits=ContactLimits(yaw_friction=False)))
    for i in range(n_ticks()):
        out = wbc.solve(*_tick(i))
        assert out.ok
        np.testing.assert_allclose(out.tau, rec["tau"][i], rtol=0, atol=2e-6)


@pytest.mark.parametrize("scale", [0.9, 0.6, 0.4])
def test_lean_qp_with_binding_torque_limits(scale: float) -> None:
    """Torque limits shrunk below the recorded torques: torque rows become active (and the
    previous tick's active set is a wrong guess for the next)."""
    rec = recording()
    for stride in (7, 3):
        limits = scale * np.abs(rec["tau"][::stride]).max(axis=0) + 0.05
        # The paper's QP on both paths (no joint relaxation when it has no solution).
        lean = WholeBodyQp(limits, WbcSettings(weight_joint=0.0))
        ref = _tight_reference(limits)
        for i in range(0, n_ticks(), stride):
            args = _tick(i)
            got = lean.solve(*args)
            want = ref.solve(*args)
            assert got.ok == want.ok, (i, got.status, want.status)
            if want.ok:
                # As above, plus proxsuite's accuracy on the rows that bind (~1e-9).
                _assert_same_output(got, want, 1e-6)
            else:
                # No relaxation in either: x = 0.
                _assert_same_output(got, want, 1e-9)


def test_lean_qp_reports_an_infeasible_problem() -> None:
    rec = recording()
    limits = ContactLimits(f_min=300.0, f_max=250.0)  # f_min > f_max: no feasible wrench
    lean = WholeBodyQp(rec["tau_limits"], WbcSettings(limits=limits))
    generic = WholeBodyQp(rec["tau_limits"], WbcSettings(limits=limits, lean=False))
    args = _tick(3)
    got = lean.solve(*args)
    want = generic.solve(*args)
    assert not got.ok and not want.ok
    assert got.status == "primal_infeasible"
    # Both fall back to no relaxation: the same torques.
    _assert_same_output(got, want, 1e-9)


def test_no_stance_foot_goes_through_the_generic_path() -> None:
    rec = recording()
    M, h, qdd, _, tau_ext = _tick(0)
    lean = WholeBodyQp(rec["tau_limits"])
    generic = WholeBodyQp(rec["tau_limits"], WbcSettings(lean=False))
    got = lean.solve(M, h, qdd, [], tau_ext)
    want = generic.solve(M, h, qdd, [], tau_ext)
    assert got.status == want.status
    # The same QP through the same backend: rounding only.
    _assert_same_output(got, want, 1e-12)


def test_the_lean_path_switches_between_stance_configurations() -> None:
    """Single and double support alternate in the recording: one workspace per count."""
    rec = recording()
    n_st = rec["stance"].sum(axis=1)
    assert {1, 2} <= set(n_st.tolist())
    wbc = WholeBodyQp(rec["tau_limits"])
    for i in range(n_ticks()):
        out = wbc.solve(*_tick(i))
        assert len(out.w5) == n_st[i]
    assert sorted(wbc._ws) == [1, 2]


def test_base_equations_hold() -> None:
    """The six unactuated rows of M qdd + h = S' tau + J' W w + tau_ext hold with the returned
    relaxations."""
    rec = recording()
    wbc = WholeBodyQp(rec["tau_limits"])
    for i in range(0, n_ticks(), 5):
        M, h, qdd, stance, tau_ext = _tick(i)
        out = wbc.solve(M, h, qdd, stance, tau_ext)
        qdd_b = qdd.copy()
        qdd_b[:6] += out.delta_base
        rhs = tau_ext.copy()
        rhs[6:] += out.tau
        for c, w5 in zip(stance, out.w5, strict=True):
            cy, sy = math.cos(c.yaw), math.sin(c.yaw)
            wrench = np.array([cy * w5[0] - sy * w5[1], sy * w5[0] + cy * w5[1], w5[2]])
            moment = rot_z(c.yaw)[:, 1:] @ w5[3:]
            rhs += c.J.T @ np.concatenate([wrench, moment])
        # Forces of ~200 N through lever arms < 1 m; 1e-8 N m is rounding.
        np.testing.assert_allclose(M @ qdd_b + h, rhs, rtol=0, atol=1e-8)


def test_stance_contact_from_world_wrench() -> None:
    rng = np.random.default_rng(0)
    for yaw in (-2.5, 0.0, 0.3, 1.7):
        wrench = rng.normal(size=6)
        c = StanceContact.from_world(np.zeros((6, NV)), yaw, wrench)
        Rz = rot_z(yaw)
        f, m = Rz.T @ wrench[:3], Rz.T @ wrench[3:]
        np.testing.assert_allclose(c.w5, [f[0], f[1], f[2], m[1], m[2]], atol=1e-15)
        assert c.yaw == yaw


def test_solve_arrays_equals_solve_and_skips_the_solver_when_nothing_binds() -> None:
    """The control loop's array form gives the same output as the list form; ticks whose
    unconstrained optimum meets every bound report 0 iterations (no DAQP call), the others
    go to DAQP, and both kinds occur on the recorded ticks."""
    rec = recording()
    wbc = WholeBodyQp(rec["tau_limits"])
    kinds = set()
    for i in range(n_ticks()):
        M, h, qdd, contacts, tau_ext = _tick(i)
        want = wbc.solve(M, h, qdd, contacts, tau_ext)
        got = wbc.solve_arrays(
            M,
            h,
            qdd,
            np.concatenate([c.J for c in contacts]),
            np.array([c.yaw for c in contacts]),
            np.concatenate([c.w5 for c in contacts]),
            tau_ext,
        )
        # The same arithmetic on the same data.
        np.testing.assert_array_equal(got.tau, want.tau)
        kinds.add(got.iterations == 0)
    assert kinds == {True, False}


@pytest.mark.parametrize("scale", [0.6, 0.3])
def test_joint_relaxation_meets_the_torque_limits_when_the_paper_qp_cannot(scale: float) -> None:
    """Torque limits shrunk until the paper's QP has no solution on some ticks: the relaxed
    QP answers there with torques within the limits, and M (qdd + delta) + h =
    S' tau + J' W w + tau_ext holds with its base and joint relaxations."""
    rec = recording()
    limits = scale * np.abs(rec["tau"]).max(axis=0) + 0.05
    strict = WholeBodyQp(limits, WbcSettings(weight_joint=0.0))
    wbc = WholeBodyQp(limits)
    n_relaxed = 0
    for i in range(0, n_ticks(), 2):
        M, h, qdd, stance, tau_ext = _tick(i)
        if strict.solve(M, h, qdd, stance, tau_ext).ok:
            continue
        out = wbc.solve(M, h, qdd, stance, tau_ext)
        assert out.ok and out.status == "solved_relaxed_joints"
        assert out.delta_joint is not None
        n_relaxed += 1
        # Bounds met to the solver's eps_abs (1e-6) after the affine map (|B| < 100).
        assert np.all(np.abs(out.tau) <= limits + 1e-4)
        qdd_r = qdd.copy()
        qdd_r[:6] += out.delta_base
        qdd_r[6:] += out.delta_joint
        rhs = tau_ext.copy()
        rhs[6:] += out.tau
        for c, w5 in zip(stance, out.w5, strict=True):
            rhs += c.J.T @ (wrench5_to_world(c.yaw) @ w5)
        # The equalities to the solver's accuracy through M (entries < 10 kg m^2).
        np.testing.assert_allclose(M @ qdd_r + h, rhs, rtol=0, atol=1e-4)
    assert n_relaxed > 0


@pytest.mark.parametrize("sigma", [1e-6, 1e-4, TASK_DAMPING**0.5, 0.1, 1.0])
def test_a_near_singular_task_commands_bounded_accelerations(sigma: float) -> None:
    """Damped least squares through a singular value sigma has gain sigma / (sigma^2 +
    lambda), at most 1 / (2 sqrt(lambda)) (reached at sigma = sqrt(lambda)): a task that the
    joints can barely move (a hand at full reach) gets a bounded command, not |r| / sigma."""
    rng = np.random.default_rng(7)
    U, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    V, _ = np.linalg.qr(rng.standard_normal((NV, NV)))
    J = U @ np.diag([1.0, 0.5, sigma]) @ V[:3]
    r = 20.0 * U[:, 2]  # 20 m/s^2 along the weak direction
    qdd = prioritized_acceleration([AccelerationTask(J, np.zeros(3), r)], NV)
    gain = sigma / (sigma**2 + TASK_DAMPING)
    assert np.linalg.norm(qdd) == pytest.approx(20.0 * gain, rel=1e-9)
    assert np.linalg.norm(qdd) <= 20.0 / (2.0 * TASK_DAMPING**0.5) * (1 + 1e-9)
