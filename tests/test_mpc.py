"""Tests of locoplan.control.mpc: prediction, statics, CoP sign, constraints, agreement between
formulations and backends, failure handling."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from locoplan.control import srbd
from locoplan.control.mpc import MpcInput, MpcSettings, MultiContactMpc
from locoplan.control.qp import BACKENDS, QpSettings
from locoplan.exceptions import SolverFailure

N = 20
MASS = 17.0
INERTIA = np.diag([0.17, 0.15, 0.06])
G = srbd.GRAVITY
Z = 0.55
FEET_SIDE = np.array([[0.0, 0.1, 0.0], [0.0, -0.1, 0.0]])
TIGHT = QpSettings(eps_abs=1e-10, eps_gap_abs=1e-10, max_iter=500, scaling=True)


def make_input(
    x_com: float = 0.0,
    feet: np.ndarray = FEET_SIDE,
    contact: np.ndarray | None = None,
    object_mass: float = 0.0,
    p_object: tuple[float, float, float] = (0.3, 0.0, 0.6),
    yaw_rate: float = 0.0,
    v0: tuple[float, float, float] = (0.0, 0.0, 0.0),
    model: str = "external-force",
) -> MpcInput:
    """At rest at the reference (CoM x_com ahead of the ankles), unless v0 pushes it."""
    x0 = np.zeros(15)
    x0[srbd.POS] = [x_com, 0.0, Z]
    x0[srbd.GRAV] = srbd.gravity_state()
    x_ref = np.tile(x0, (N, 1))
    yaw = yaw_rate * 0.03 * np.arange(1, N + 1)
    x_ref[:, 2] = yaw
    x_ref[:, 8] = yaw_rate
    x0[srbd.VEL] = v0
    return MpcInput(
        x0=x0,
        x_ref=x_ref,
        contact=np.ones((N, 2), dtype=bool) if contact is None else contact,
        p_feet=np.tile(feet, (N, 1, 1)),
        foot_yaw=np.tile(np.r_[0.0, 0.0] if yaw_rate == 0 else [0.3, 0.4], (N, 1)),
        yaw_lin=np.r_[0.0, yaw[:-1]],
        mass=MASS,
        inertia_body=INERTIA,
        object_held=np.full(N, object_mass > 0),
        object_mass=object_mass,
        p_object=np.tile(p_object, (N, 1)),
        model=model,
    )


def stepping_contact() -> np.ndarray:
    t = 0.03 * np.arange(N)
    ph = np.mod(t, 0.4)
    return np.stack([~((ph >= 0.05) & (ph < 0.2)), ~((ph >= 0.25) & (ph < 0.4))], axis=1)


def net_moment_about_com(inp: MpcInput, U0: np.ndarray) -> np.ndarray:
    """Moment (3,) about the CoM of the first step's foot wrenches and the held load."""
    p_c = inp.x0[srbd.POS]
    total = np.zeros(3)
    for f in range(2):
        R = srbd.rot_z(float(inp.foot_yaw[0, f]))
        total += np.cross(inp.p_feet[0, f] - p_c, U0[f, 0:3])
        total += R @ srbd.L_SELECT @ U0[f, 3:5]
    m_o = float(np.asarray(inp.object_mass))
    if inp.object_held[0] and m_o > 0 and inp.p_object is not None:
        total += np.cross(inp.p_object[0] - p_c, [0.0, 0.0, -m_o * G])
    return total


def rollout_with(inp: MpcInput, U: np.ndarray, levers: np.ndarray | None = None) -> np.ndarray:
    """x_1..x_N by srbd.rollout with the returned U (the reference model, one step at a time);
    step k >= 1's lever arms from ``levers[k - 1]`` (N, 3) if given, else from x_ref[k - 1]."""
    models = []
    u = np.zeros((N, 10))
    lev = inp.x_ref[:, srbd.POS] if levers is None else levers
    for k in range(N):
        p_c = inp.x0[srbd.POS] if k == 0 else lev[k - 1]
        cm = srbd.continuous_model(
            float(inp.yaw_lin[k]),
            p_c,
            inp.p_feet[k],
            inp.foot_yaw[k],
            inp.contact[k],
            inp.mass,
            inp.inertia_body,
            bool(inp.object_held[k]),
            float(np.asarray(inp.object_mass)),
            None if inp.p_object is None else inp.p_object[k],
            inp.model,
        )
        models.append(srbd.discretize(cm, 0.03))
        u[k] = srbd.input_vector(U[k, :, 0:3], U[k, :, 3:5])
    return srbd.rollout(models, inp.x0, u)


@pytest.mark.parametrize("model", ["external-force", "combined"])
@pytest.mark.parametrize("formulation", ["condensed", "sparse"])
def test_prediction_is_the_rollout_of_the_returned_inputs(model: str, formulation: str) -> None:
    inp = make_input(
        contact=stepping_contact(),
        object_mass=3.0,
        yaw_rate=0.5,
        v0=(0.1, -0.05, 0.0),
        model=model,
    )
    sol = MultiContactMpc(MpcSettings(formulation=formulation)).update(inp)
    assert sol.ok
    # Both sides are exact ZOH of the same linear model; 1e-9 covers rounding on states <= 10.
    np.testing.assert_allclose(sol.X, rollout_with(inp, sol.U), rtol=0, atol=1e-9)


def test_static_double_stance_at_rest() -> None:
    inp = make_input()
    sol = MultiContactMpc().update(inp)
    assert sol.ok and sol.fallback == "none"
    F = sol.forces_world
    # R = 1e-4 pulls every force towards zero and the state cost resists a deficit only
    # through the sag it causes over the horizon, so the optimum under-supports by a fraction
    # of a newton (0.29 N measured); 1 N = 0.6 % of m g bounds that.
    assert abs(F[:, 2].sum() - MASS * G) < 1.0
    # Symmetric problem: equal split to solver accuracy (eps 1e-6 on scaled residuals).
    assert abs(F[0, 2] - F[1, 2]) < 1e-4
    np.testing.assert_allclose(F[:, 0:2], 0.0, atol=1e-6)
    for f in range(2):
        My = sol.U[0, f, 3]
        assert -0.09 * F[f, 2] - 1e-9 <= My <= 0.06 * F[f, 2] + 1e-9
    # At rest at the reference nothing asks for a moment: |M| below 1e-6 N m.
    np.testing.assert_allclose(sol.moments_world, 0.0, atol=1e-6)
    np.testing.assert_allclose(net_moment_about_com(inp, sol.U[0]), 0.0, atol=1e-6)


def test_held_object_model2_loads_the_toes() -> None:
    m_o, d = 3.0, 0.3
    inp = make_input(object_mass=m_o, p_object=(d, 0.0, 0.6))
    sol = MultiContactMpc().update(inp)
    assert sol.ok
    F = sol.forces_world
    # Same 1 N bound as the static test (measured deficit 0.34 N with the load).
    assert abs(F[:, 2].sum() - (MASS + m_o) * G) < 1.0
    # Toe loading: My < 0, and the centre of pressure moves forward by m_o d / (m + m_o),
    # which balances the load's moment about the CoM. 1 mm covers the force deficit above.
    x_cop = -sol.U[0, :, 3] / F[:, 2]
    assert np.all(sol.U[0, :, 3] < 0)
    np.testing.assert_allclose(x_cop, m_o * d / (MASS + m_o), atol=1e-3)
    # Static equilibrium about the CoM: a residual below 0.1 N m (0.34 N deficit x 0.3 m lever
    # at most) means the feet balance the load's 8.8 N m.
    assert np.linalg.norm(net_moment_about_com(inp, sol.U[0])) < 0.1


def test_held_object_staggered_feet_combined_cop_under_load_shift() -> None:
    m_o, d = 3.0, 0.3
    feet = np.array([[0.08, 0.1, 0.0], [-0.08, -0.1, 0.0]])
    inp = make_input(feet=feet, object_mass=m_o, p_object=(d, 0.0, 0.6))
    sol = MultiContactMpc().update(inp)
    F, My = sol.forces_world, sol.U[0, :, 3]
    # Combined CoP of both feet (vertical forces and ankle moments) sits m_o d / (m + m_o)
    # ahead of the CoM: the support shifts towards the front foot/toes (1 mm as above).
    x_cop = float((feet[:, 0] @ F[:, 2] - My.sum()) / F[:, 2].sum())
    assert x_cop == pytest.approx(m_o * d / (MASS + m_o), abs=1e-3)
    assert np.linalg.norm(net_moment_about_com(inp, sol.U[0])) < 0.1


def test_cop_sign_com_ahead_of_feet() -> None:
    # CoM 3 cm ahead of the ankles: gravity tips the robot forward, so the feet must push
    # at the toes. The moment on the robot is My = -x_cop Fz < 0 with x_cop = +0.03.
    inp = make_input(x_com=0.03)
    sol = MultiContactMpc().update(inp)
    U0 = sol.U[0]
    assert np.all(U0[:, 3] < 0.0)
    np.testing.assert_allclose(-U0[:, 3] / U0[:, 2], 0.03, atol=1e-3)
    # Physics: the wrench's net moment about the CoM vanishes (static balance). With the
    # opposite sign convention it would double instead (2 x 2 x 2.5 N m).
    assert np.linalg.norm(net_moment_about_com(inp, U0)) < 0.05


def test_cop_saturates_at_the_toe() -> None:
    # CoM 12 cm ahead: beyond the 9 cm toe. The CoP constraint must hold at the toe bound
    # (My = -toe Fz, active) -- a flipped constraint would put it at the heel or beyond.
    inp = make_input(x_com=0.12)
    sol = MultiContactMpc(MpcSettings(qp=TIGHT)).update(inp)
    U0 = sol.U[0]
    np.testing.assert_allclose(-U0[:, 3] / U0[:, 2], 0.09, atol=1e-6)


def test_swing_feet_have_exactly_zero_wrench() -> None:
    contact = stepping_contact()
    sol = MultiContactMpc().update(make_input(contact=contact, v0=(0.05, 0.1, 0.0)))
    assert sol.ok
    assert np.all(sol.U[~contact] == 0.0)
    assert np.all(sol.U[contact][:, 2] > 0.0)
    swing0 = ~contact[0]
    assert np.all(sol.forces_world[swing0] == 0.0) and np.all(sol.moments_world[swing0] == 0.0)


@pytest.mark.parametrize("backend", BACKENDS)
def test_bounds_hold_on_every_step_under_a_push(backend: str) -> None:
    s = MpcSettings(backend=backend, mu_torsion=0.02)
    inp = make_input(contact=stepping_contact(), v0=(0.6, -0.4, 0.0), yaw_rate=0.5)
    sol = MultiContactMpc(s).update(inp)
    assert sol.ok
    active_found = False
    # Tolerances: the solvers accept bound violations up to eps_abs = 1e-6 in the scaled
    # problem, i.e. about 1e-4 N for forces of O(100) N; 1e-3 N / N m is a safe margin.
    tol = 1e-3
    for k in range(N):
        for f in range(2):
            if not inp.contact[k, f]:
                continue
            R = srbd.rot_z(float(inp.foot_yaw[k, f]))
            Fx, Fy, Fz = R.T @ sol.U[k, f, 0:3]
            My, Mz = sol.U[k, f, 3:5]
            assert abs(Fx) <= s.mu * Fz + tol and abs(Fy) <= s.mu * Fz + tol
            assert s.f_min - tol <= Fz <= s.f_max + tol
            assert -s.toe * Fz - tol <= My <= s.heel * Fz + tol
            assert abs(Mz) <= 0.02 * Fz + tol
            active_found |= abs(Fy) > s.mu * Fz - tol or abs(Fx) > s.mu * Fz - tol
            active_found |= Fz > s.f_max - tol or My < -s.toe * Fz + tol
    assert active_found, "the push should make some bound active"


@pytest.mark.parametrize(
    "inp",
    [
        make_input(x_com=0.02, v0=(0.2, 0.1, 0.0)),
        make_input(contact=stepping_contact(), v0=(0.6, -0.4, 0.0), yaw_rate=0.5),
        make_input(contact=stepping_contact(), object_mass=4.0, yaw_rate=-0.3),
    ],
)
def test_formulations_and_backends_agree(inp: MpcInput) -> None:
    # daqp on the condensed form takes the MPC's least-distance form; on the sparse form it
    # gets the plain (densified) problem.
    results = {}
    for formulation in ("condensed", "sparse"):
        for backend in BACKENDS:
            s = MpcSettings(formulation=formulation, backend=backend, qp=TIGHT)
            sol = MultiContactMpc(s).update(inp)
            assert sol.ok, (formulation, backend, sol.status)
            results[(formulation, backend)] = sol.U
    ref = results[("condensed", "piqp")]
    for key, U in results.items():
        # 1e-5 relative on the whole horizon: the QP is ill-conditioned (R = 1e-4 against
        # state weights up to 2000, cond(H) ~ 1e7), so at eps 1e-10 the solutions agree to
        # ~1e-7 relative; different algorithms stop at slightly different points.
        rel = np.linalg.norm(U - ref) / np.linalg.norm(ref)
        assert rel < 1e-5, (key, rel)


def test_infeasible_settings_fail_cleanly() -> None:
    # f_min > f_max: every QP is infeasible. With fallbacks the relaxed QP (f_min = 0) gives
    # forces and the failure is reported; without, SolverFailure is raised.
    bad = MpcSettings(f_min=300.0, f_max=250.0)
    sol = MultiContactMpc(bad).update(make_input())
    assert not sol.ok and sol.status != "solved" and sol.fallback == "relaxed"
    assert np.all(sol.U[0, :, 2] <= 250.0 + 1e-3)
    with pytest.raises(SolverFailure) as err:
        MultiContactMpc(replace(bad, fallback=False)).update(make_input())
    assert err.value.problem == "mpc" and err.value.status != "solved"


def test_shifted_fallback_and_final_failure() -> None:
    # daqp capped at one iteration: the first (rest) problem needs no active constraint (its
    # unconstrained minimiser meets every bound) and solves; the pushed one cannot, nor can
    # its relaxed retry, so the previous solution is shifted by one step.
    qp = QpSettings(max_iter=1)
    s = MpcSettings(backend="daqp", qp=qp, relaxed_qp=qp)
    mpc = MultiContactMpc(s)
    first = mpc.update(make_input())  # t = 0
    assert first.ok
    pushed = replace(make_input(contact=stepping_contact(), v0=(0.6, -0.4, 0.0)), t=0.03)
    sol = mpc.update(pushed)
    assert not sol.ok and sol.fallback == "shifted"
    np.testing.assert_allclose(sol.U[0, 0], first.U[1, 0])
    assert np.all(sol.U[~pushed.contact] == 0.0)
    with pytest.raises(SolverFailure):
        MultiContactMpc(s).update(pushed)


def test_input_validation() -> None:
    inp = make_input()
    with pytest.raises(ValueError):
        replace(inp, contact=np.ones((N - 1, 2), dtype=bool))
    with pytest.raises(ValueError):
        replace(inp, model="bogus")
    with pytest.raises(ValueError):
        MultiContactMpc(MpcSettings(horizon=10)).update(inp)
    with pytest.raises(ValueError):
        MpcSettings(dt=0.0)


@pytest.mark.parametrize("warm_start", [False, True])
def test_consecutive_updates_match_fresh_solves(warm_start: bool) -> None:
    # Later updates re-use the cached factor blocks and, with warm_start, start daqp from
    # the previous active set (shifted by the elapsed steps); the optimum must not depend on
    # either.
    s = MpcSettings()
    mpc = MultiContactMpc(replace(s, qp=replace(s.qp, warm_start=warm_start)))
    contact = stepping_contact()
    for i, v in enumerate([(0.3, -0.3, 0.0), (0.35, -0.25, 0.0), (0.2, -0.3, 0.1)]):
        inp = replace(make_input(contact=contact, v0=v), t=0.03 * i)
        warm = mpc.update(inp)
        fresh = MultiContactMpc().update(inp)
        assert warm.ok and fresh.ok
        assert warm.iterations > 0  # the push makes bounds active: daqp ran
        # Both solve to eps_abs = 1e-6 on the bounds and are exact otherwise; the QP is
        # ill-conditioned (cond ~1e7), so 1e-5 relative on U.
        rel = np.linalg.norm(warm.U - fresh.U) / np.linalg.norm(fresh.U)
        assert rel < 1e-5


@pytest.mark.parametrize("stance_at_0", [False, True])
def test_least_distance_edge_schedules(stance_at_0: bool) -> None:
    # The least-distance form splits step 0's variables off the cached leading block: check
    # the split when either side is empty (flight at step 0 only; stance at step 0 only).
    contact = np.full((N, 2), not stance_at_0)
    contact[0] = stance_at_0
    inp = make_input(contact=contact, v0=(0.3, -0.2, 0.0))
    sol = MultiContactMpc(MpcSettings(qp=TIGHT)).update(inp)
    ref = MultiContactMpc(MpcSettings(backend="piqp", qp=TIGHT)).update(inp)
    assert sol.ok and ref.ok
    # 1e-5 relative as in test_formulations_and_backends_agree (cond(H) ~ 1e7).
    assert np.linalg.norm(sol.U - ref.U) / np.linalg.norm(ref.U) < 1e-5


def _sinking(t: float = 0.0) -> MpcInput:
    """Stepping, with the reference 0.12 m below the CoM: the QP wants the feet unloaded."""
    inp = make_input(contact=stepping_contact(), v0=(0.2, -0.1, 0.0))
    x_ref = inp.x_ref.copy()
    x_ref[:, 5] -= 0.12  # z of the CoM (srbd.POS = 3:6)
    return replace(inp, x_ref=x_ref, t=t)


def _summed_fz(U: np.ndarray, contact: np.ndarray) -> np.ndarray:
    return np.where(contact, U[:, :, 2], 0.0).sum(axis=1)


def test_support_fraction_bounds_the_summed_vertical_force() -> None:
    inp = _sinking()
    need = 0.6 * MASS * G
    free = MultiContactMpc(MpcSettings(qp=TIGHT)).update(inp)
    assert free.ok
    # Without the bound the QP takes both feet to f_min at the first steps (the test's premise).
    assert _summed_fz(free.U, inp.contact).min() < 0.5 * need
    results = {}
    for formulation in ("condensed", "sparse"):
        for backend in BACKENDS:
            s = MpcSettings(
                formulation=formulation, backend=backend, qp=TIGHT, support_fraction=0.6
            )
            sol = MultiContactMpc(s).update(inp)
            assert sol.ok and sol.fallback == "none", (formulation, backend, sol.status)
            # 1e-3 N: the solvers' eps_abs (1e-10 here) on forces of O(100) N, with margin.
            assert _summed_fz(sol.U, inp.contact).min() >= need - 1e-3, (formulation, backend)
            assert np.all(sol.U[inp.contact][:, 2] >= s.f_min - 1e-3)
            results[(formulation, backend)] = sol.U
    ref = results[("condensed", "piqp")]
    for key, U in results.items():
        # As in test_formulations_and_backends_agree (cond(H) ~ 1e7).
        assert np.linalg.norm(U - ref) / np.linalg.norm(ref) < 1e-5, key


def test_support_fraction_with_warm_starts_and_the_relaxed_retry() -> None:
    # The summed rows come after the wrench rows: the shifted active set of the previous
    # update (daqp's warm start) must skip them and still reach the fresh optimum.
    s = MpcSettings(support_fraction=0.6)
    mpc = MultiContactMpc(s)
    for i in range(3):
        inp = _sinking(0.03 * i)
        warm = mpc.update(inp)
        fresh = MultiContactMpc(replace(s, qp=replace(s.qp, warm_start=False))).update(inp)
        assert warm.ok and fresh.ok
        assert np.linalg.norm(warm.U - fresh.U) / np.linalg.norm(fresh.U) < 1e-5
    # f_min > f_max: the relaxed retry (f_min = 0, the summed rows at 0 N) still gives forces.
    bad = MpcSettings(f_min=300.0, f_max=250.0, support_fraction=0.6)
    sol = MultiContactMpc(bad).update(_sinking())
    assert not sol.ok and sol.fallback == "relaxed"
    with pytest.raises(ValueError):
        MpcSettings(support_fraction=1.5)


def _ahead(t: float, x_ahead: float = 0.04) -> MpcInput:
    """Standing with 3 kg held, the CoM ``x_ahead`` in front of its reference (after a pick)."""
    inp = make_input(object_mass=3.0, p_object=(0.25, 0.0, 0.6))
    x0 = inp.x0.copy()
    x0[3] += x_ahead
    return replace(inp, x0=x0, t=t)


def test_predicted_levers_are_the_previous_prediction() -> None:
    # One whole step later, step k's lever arm is the previous prediction's CoM x_k exactly
    # (row k - 1 of levers is X_prev[k]); the last row is past the previous horizon.
    mpc = MultiContactMpc(MpcSettings(qp=TIGHT, levers="predicted"))
    first = mpc.update(_ahead(0.0))
    inp = _ahead(0.03)
    second = mpc.update(inp)
    levers = np.vstack([first.X[1:, srbd.POS], inp.x_ref[-1:, srbd.POS]])
    X = rollout_with(inp, second.U, levers)
    # 1e-9: the ZOH discretisations of srbd (expm) and of the kernels (closed form) agree to
    # rounding; states are O(1) m and rad.
    assert np.abs(second.X[:, :12] - X[:, :12]).max() < 1e-9
    # The reference levers are a different problem: the same U rolls out elsewhere.
    assert np.abs(rollout_with(inp, second.U)[:, :12] - X[:, :12]).max() > 1e-6
    # A third of a step later the levers are interpolated between the prediction's steps.
    path = mpc._lever_path(_ahead(0.04))
    assert path is not None
    want = (2.0 / 3.0) * second.X[0, srbd.POS] + (1.0 / 3.0) * second.X[1, srbd.POS]
    assert np.allclose(path[0], want, atol=1e-12)
    # The reference levers ignore the prediction.
    assert MultiContactMpc(MpcSettings(levers="reference"))._lever_path(inp) is None
    # "stepping": the prediction's levers only while a foot swings within the horizon.
    stepping = MultiContactMpc(MpcSettings(qp=TIGHT, levers="stepping"))
    stepping.update(_ahead(0.0))
    assert stepping._lever_path(_ahead(0.03)) is None  # both feet stand throughout
    swinging = replace(_ahead(0.03), contact=stepping_contact())
    predicted = MultiContactMpc(MpcSettings(qp=TIGHT, levers="predicted"))
    predicted.update(_ahead(0.0))
    got, want = stepping._lever_path(swinging), predicted._lever_path(swinging)
    assert got is not None and want is not None and np.array_equal(got, want)
    with pytest.raises(ValueError):
        MpcSettings(levers="measured")


def test_predicted_levers_keep_the_support_steady_with_the_com_ahead() -> None:
    # With the CoM 4 cm ahead of its reference, step 0's lever arm (measured CoM) and step
    # 1's (reference) differ by 4 cm: the QP takes weight off the feet now and puts it on the
    # next step (what sank the trunk after heavy picks in the envelope, mpc._lever_path).
    # Levers from the previous prediction converge, update by update, to a steady support.
    weight = (MASS + 3.0) * G
    jumps = {}
    for levers in ("reference", "predicted"):
        mpc = MultiContactMpc(MpcSettings(qp=TIGHT, levers=levers))
        for i in range(8):
            sol = mpc.update(_ahead(0.01 * i))
            assert sol.ok and sol.fallback == "none"
        fz = sol.U[:, :, 2].sum(axis=1)
        jumps[levers] = abs(fz[1] - fz[0]) / weight
    # Measured 0.18 (reference) and 0.037 (predicted) of the weight.
    assert jumps["reference"] > 0.12
    assert jumps["predicted"] < 0.08
