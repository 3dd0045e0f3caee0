"""Tests of locoplan.control.mpc_kernels and the MPC path built on them.

The compiled Hessian, gradient and free rollout are checked against the plain condensed
formulas (prediction matrix G from `srbd`'s per-step discrete models: H = G'QG + R,
g = G'Q(x_free - x_ref)); the structured Cholesky factor and the least-distance form against
their definitions; and the MPC's solutions on recorded closed-loop inputs against the
solutions of the implementation before the kernels (numpy and LAPACK, commit 69f8286) and
against piqp on the plain QP. Every kernel is called here, so none compiles for the first
time inside a closed loop; the last test checks that each was compiled once only (no input
dtype or layout slips through to a second specialisation at run time).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from numba.core.registry import CPUDispatcher

from locoplan.control import mpc_kernels, srbd
from locoplan.control.mpc import MpcInput, MpcSettings, MultiContactMpc
from locoplan.control.mpc_terms import propagate, step_terms
from locoplan.control.qp import QpProblem, QpSettings, QpSolver

N = 20
DT = 0.03
MASS = 17.0
INERTIA = np.diag([0.17, 0.15, 0.06])
DATA = Path(__file__).parent / "data" / "mpc_recorded_inputs.npz"
# The controller's MPC settings (ControllerSettings().mpc: torsion bound from ContactLimits);
# the recorded solutions were computed with them.
# The recorded solutions were solved without the centre-of-pressure dependent yaw friction
# rows (added later): the same QP needs them off.
CONTROLLER_MPC = MpcSettings(mu_torsion=0.02, yaw_friction=False)
TIGHT = QpSettings(eps_abs=1e-10, eps_gap_abs=1e-10, max_iter=500, scaling=True)


def stepping_contact(phase: float = 0.0) -> np.ndarray:
    t = phase + DT * np.arange(N)
    ph = np.mod(t, 0.4)
    return np.stack([~((ph >= 0.05) & (ph < 0.2)), ~((ph >= 0.25) & (ph < 0.4))], axis=1)


def synthetic_input(
    model: str = "external-force",
    object_mass: float = 0.0,
    yaw_rate: float = 0.0,
    contact: np.ndarray | None = None,
    seed: int = 0,
) -> MpcInput:
    """A stepping, turning, pushed robot with the load held from step 3 on (if any)."""
    rng = np.random.default_rng(seed)
    x0 = np.zeros(15)
    x0[srbd.POS] = [0.01, -0.02, 0.55]
    x0[srbd.GRAV] = srbd.gravity_state()
    x0[0:3] = rng.normal(scale=0.02, size=3)
    x0[srbd.OMEGA] = rng.normal(scale=0.2, size=3)
    x0[srbd.VEL] = [0.3, -0.1, 0.02]
    x_ref = np.tile(x0, (N, 1))
    x_ref[:, srbd.VEL] = [0.2, 0.0, 0.0]
    x_ref[:, 3] = 0.01 + 0.2 * DT * np.arange(1, N + 1)
    yaw = yaw_rate * DT * np.arange(1, N + 1)
    x_ref[:, 2] = yaw
    x_ref[:, 8] = yaw_rate
    x_ref[:, 6:8] = 0.0
    feet = np.array([[0.05, 0.1, 0.0], [-0.03, -0.1, 0.01]])
    p_feet = np.tile(feet, (N, 1, 1)) + rng.normal(scale=0.01, size=(N, 2, 3))
    held = np.arange(N) >= 3
    return MpcInput(
        x0=x0,
        x_ref=x_ref,
        contact=stepping_contact(0.1) if contact is None else contact,
        p_feet=p_feet,
        foot_yaw=np.tile([0.2, -0.1], (N, 1)) + yaw[:, None],
        yaw_lin=np.r_[0.0, yaw[:-1]],
        mass=MASS,
        inertia_body=INERTIA + np.diag([0.0, 0.0, 0.01]),
        object_held=held & (object_mass > 0),
        object_mass=np.where(held, object_mass, 0.0),
        p_object=x_ref[:, srbd.POS] + [0.3, 0.05, 0.05],
        model=model,
    )


CASES = {
    "model2-no-object": synthetic_input(),
    "model2-held-turning": synthetic_input(object_mass=4.0, yaw_rate=0.6),
    "model1-held-turning": synthetic_input("combined", object_mass=4.0, yaw_rate=-0.5, seed=1),
    "model1-no-object": synthetic_input("combined", yaw_rate=0.3, seed=2),
}


def recorded_inputs() -> list[tuple[str, MpcInput, np.ndarray, int]]:
    """(source, input, U of the implementation before the kernels, its iterations)."""
    d = np.load(DATA)
    out = []
    for i in range(d["mass"].shape[0]):
        inp = MpcInput(
            x0=d["x0"][i],
            x_ref=d["x_ref"][i],
            contact=d["contact"][i],
            p_feet=d["p_feet"][i],
            foot_yaw=d["foot_yaw"][i],
            yaw_lin=d["yaw_lin"][i],
            mass=float(d["mass"][i]),
            inertia_body=d["inertia_body"][i],
            object_held=d["object_held"][i],
            object_mass=d["object_mass"][i],
            p_object=d["p_object"][i],
            model=str(d["model"][i]),
            t=float(d["t"][i]),
        )
        out.append((f"{d['source'][i]}-{i}", inp, d["U_before"][i], int(d["iterations_before"][i])))
    return out


RECORDED = recorded_inputs()


def reference_qp(inp: MpcInput, s: MpcSettings) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(H, g, x_free) of the condensed QP the plain way, in the MPC's variable order.

    G column j is the response of x_1..x_N to a unit foot-frame wrench component through
    `srbd`'s exact per-step discrete models (affine terms dropped); x_free the rollout with
    zero contact wrenches (affine terms kept).
    """
    m_o = np.broadcast_to(np.asarray(inp.object_mass, dtype=float), (N,))
    models = []
    for k in range(N):
        p_c = inp.x0[srbd.POS] if k == 0 else inp.x_ref[k - 1, srbd.POS]
        cm = srbd.continuous_model(
            float(inp.yaw_lin[k]),
            p_c,
            inp.p_feet[k],
            inp.foot_yaw[k],
            inp.contact[k],
            inp.mass,
            inp.inertia_body,
            bool(inp.object_held[k]),
            float(m_o[k]),
            None if inp.p_object is None else inp.p_object[k],
            inp.model,
        )
        models.append(srbd.discretize(cm, s.dt))
    x_free = srbd.rollout(models, inp.x0, np.zeros((N, 10)))
    linear = [replace(dm, d=np.zeros(15)) for dm in models]
    # The MPC's order: stance (k, foot) from step N-1 down to 0; five components each.
    order = [(k, f) for k in range(N - 1, -1, -1) for f in range(2) if inp.contact[k, f]]
    r = np.asarray(s.r_diag)
    r_foot = [np.r_[r[0:3], r[6:8]], np.r_[r[3:6], r[8:10]]]
    cols, rdiag = [], []
    for k, f in order:
        R_f = srbd.rot_z(float(inp.foot_yaw[k, f]))
        for a in range(5):
            u = np.zeros((N, 10))
            if a < 3:
                u[k, 3 * f : 3 * f + 3] = R_f[:, a]
            else:
                u[k, 6 + 2 * f + (a - 3)] = 1.0
            cols.append(srbd.rollout(linear, np.zeros(15), u).reshape(-1))
            rdiag.append(r_foot[f][a])
    G = np.array(cols).T
    q = np.tile(np.asarray(s.q_diag), N)
    H = G.T @ (q[:, None] * G) + np.diag(rdiag)
    g = G.T @ (q * (x_free - inp.x_ref).reshape(-1))
    return H, g, x_free


def rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


@pytest.mark.parametrize("name", list(CASES))
def test_condensed_qp_matches_the_prediction_matrix(name: str) -> None:
    inp = CASES[name]
    s = MpcSettings()
    qp = MultiContactMpc(s).build_qp(inp)
    H_ref, g_ref, _ = reference_qp(inp, s)
    assert qp.H.shape == H_ref.shape
    # Both are float64 sums of the same products in different orders (the semi-separable
    # generators are larger than the entries they make): rounding of a few ulps of the
    # largest entry (measured 1.1e-15 for H, 4e-16 for g); 1e-13 leaves a 100x margin.
    scale = np.abs(H_ref).max()
    np.testing.assert_allclose(qp.H, H_ref, rtol=0, atol=1e-13 * scale)
    assert np.array_equal(qp.H, qp.H.T)
    np.testing.assert_allclose(qp.g, g_ref, rtol=0, atol=1e-13 * np.abs(g_ref).max())


@pytest.mark.parametrize("name", list(CASES))
def test_prediction_matches_the_reference_rollout(name: str) -> None:
    inp = CASES[name]
    s = MpcSettings()
    _, _, x_free = reference_qp(inp, s)
    # The free rollout against srbd's step by step: exact ZOH on both sides, rounding only
    # (measured 7e-15 on states of order 1).
    mpc = MultiContactMpc(s)
    Ib = np.ascontiguousarray(inp.inertia_body)
    kern = mpc._get_kernel(np.ascontiguousarray(inp.yaw_lin), Ib)
    st = step_terms(inp, s.dt, kern.Iinv, Ib)
    X0 = propagate(inp.x0, kern.RzT, st.Iinv, st.mass, st.tau_ext, st.f_ext, s.dt)
    np.testing.assert_allclose(X0, x_free, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", list(CASES))
def test_structured_factor_and_least_distance_form(name: str) -> None:
    inp = CASES[name]
    s = MpcSettings()
    mpc = MultiContactMpc(s)
    qp = mpc.build_qp(inp)
    Ib = np.ascontiguousarray(inp.inertia_body)
    kern = mpc._get_kernel(np.ascontiguousarray(inp.yaw_lin), Ib)
    st = step_terms(inp, s.dt, kern.Iinv, Ib)
    x_free = propagate(inp.x0, kern.RzT, st.Iinv, st.mass, st.tau_ext, st.f_ext, s.dt)
    qp2, Lam, Gam = mpc._condensed(inp, st, kern, x_free, s.f_min, s.f_max)
    np.testing.assert_array_equal(qp2.H, qp.H)
    form = mpc._least_distance(qp, Lam, Gam, st.cols)
    assert form is not None
    # x_u = -H^-1 g: cond(H) ~ 3e7 turns rounding into ~1e-11 relative differences between
    # LAPACK's LU and the structured factor (measured <= 4e-11).
    x_ref = np.linalg.solve(qp.H, -qp.g)
    assert rel(form.x_u, x_ref) < 1e-9
    assert form.box is not None
    U = form.factor()
    W = form.rows(np.arange(form.box.shape[0] + qp.n_in))
    # U'HU = I: U = L^-T has the condition number cond(H)^1/2 ~ 5e3, so products lose about
    # 1e-16 * cond(H) (measured <= 1.5e-10).
    np.testing.assert_allclose(U.T @ qp.H @ U, np.eye(qp.n), rtol=0, atol=1e-9)
    assert qp.C is not None
    np.testing.assert_array_equal(form.box, np.flatnonzero(np.isfinite(qp.x_lower)))
    # W = [U[box]; C U], the same sums in another order (entries of order 1e-1).
    np.testing.assert_allclose(W, np.vstack([U[form.box], qp.C @ U]), rtol=0, atol=1e-13)
    # The dense factor is L with H = L L'.
    start, size = mpc_kernels.factor_blocks(st.cols)
    L_diag, Z, ok = mpc_kernels.factor(qp.H, Gam, Lam, start, size)
    assert ok
    L = mpc_kernels.dense_factor(Gam, L_diag, Z, start, size)
    # Backward-stable Cholesky: a few ulps of the largest entry (measured 1.3e-15).
    np.testing.assert_allclose(L @ L.T, qp.H, rtol=0, atol=1e-13 * np.abs(qp.H).max())
    assert np.array_equal(L, np.tril(L))
    np.testing.assert_allclose(U, np.linalg.inv(L).T, rtol=0, atol=1e-12 * np.abs(U).max())


@pytest.mark.parametrize(
    ("name", "inp", "U_before", "iters"), RECORDED, ids=[r[0] for r in RECORDED]
)
def test_recorded_inputs_give_the_solutions_of_before(
    name: str, inp: MpcInput, U_before: np.ndarray, iters: int
) -> None:
    sol = MultiContactMpc(CONTROLLER_MPC).update(inp)
    assert sol.ok and sol.fallback == "none"
    # Same QP, same solver (DAQP is exact once it stops on an active set): H and its factor
    # differ from before by rounding only, which cond(H) ~ 3e7 turns into ~1e-11 relative
    # on U (measured <= 6e-12 on all 2654 recorded updates of walk-square and
    # package-transfer, both models, 5e-11 with standing-load's 14 kg); 1e-9 leaves room for
    # another BLAS.
    assert rel(sol.U, U_before) < 1e-9, name


@pytest.mark.parametrize(
    ("name", "inp", "U_before", "iters"),
    [r for r in RECORDED if r[3] > 0],
    ids=[r[0] for r in RECORDED if r[3] > 0],
)
def test_recorded_inputs_match_an_independent_solver(
    name: str, inp: MpcInput, U_before: np.ndarray, iters: int
) -> None:
    # The constrained recorded problems: piqp (interior point) on the plain QP from srbd.
    s = replace(CONTROLLER_MPC, qp=TIGHT)
    mpc = MultiContactMpc(s)
    ref = mpc.build_qp(inp)
    H, g, _ = reference_qp(inp, s)
    plain = QpProblem(H=H, g=g, C=ref.C, l=ref.l, u=ref.u, x_lower=ref.x_lower, x_upper=ref.x_upper)
    other = QpSolver("piqp", TIGHT).solve(plain)
    sol = mpc.update(inp)
    assert other.ok and sol.ok
    # 1e-5 relative as in test_mpc.test_formulations_and_backends_agree (cond(H) ~ 1e7,
    # different algorithms stop at slightly different points).
    assert rel(sol.qp.x if sol.qp is not None else sol.U, other.x) < 1e-5, name


def test_no_stance_and_single_block_schedules() -> None:
    # Flight over the whole horizon (no variables) and stance at one step only (one block).
    mpc = MultiContactMpc()
    flight = synthetic_input(contact=np.zeros((N, 2), dtype=bool))
    sol = mpc.update(flight)
    assert sol.ok and sol.status == "no_contact" and not np.any(sol.U)
    for k in (0, 7):
        contact = np.zeros((N, 2), dtype=bool)
        contact[k] = True
        inp = synthetic_input(contact=contact)
        H, g, _ = reference_qp(inp, mpc.settings)
        got = MultiContactMpc().update(inp)
        want = QpSolver("piqp", TIGHT).solve(
            replace(mpc.build_qp(inp), H=H, g=g)  # same bounds, plain H and g
        )
        assert got.qp is not None and got.ok and want.ok
        assert rel(got.qp.x, want.x) < 1e-5


def test_odd_input_types_reuse_the_compiled_kernels() -> None:
    # float32, Fortran-ordered and integer inputs are converted before the kernels, and every
    # kernel called from Python was compiled for one signature only.
    base = CASES["model2-held-turning"]
    odd = replace(
        base,
        x_ref=base.x_ref.astype(np.float32),
        p_feet=np.asfortranarray(base.p_feet),
        inertia_body=np.asfortranarray(base.inertia_body),
        object_mass=3,
        p_object=None if base.p_object is None else base.p_object[:, :].copy(order="F"),
        mass=17,
    )
    assert MultiContactMpc().update(odd).ok
    for name in dir(mpc_kernels):
        kernel = getattr(mpc_kernels, name)
        if isinstance(kernel, CPUDispatcher) and not name.startswith("_"):
            assert len(kernel.signatures) <= 1, (name, kernel.signatures)


def test_held_object_inertia_enters_the_external_wrench() -> None:
    # Model 2 with a planned object acceleration a: the hands feel m_o (g - a) at the object,
    # f_ext = m_o (-a_x, -a_y, -(g + a_z)) and tau_ext = (p_object - p_com) x f_ext; with
    # a = 0 it is the weight alone. Exact arithmetic on a few products (rounding only).
    inp = synthetic_input(object_mass=3.0)
    s = MpcSettings()
    mpc = MultiContactMpc(s)
    Ib = np.ascontiguousarray(inp.inertia_body)
    kern = mpc._get_kernel(np.ascontiguousarray(inp.yaw_lin), Ib)
    rest = step_terms(inp, s.dt, kern.Iinv, Ib)
    a = np.tile([1.5, -2.0, 0.7], (N, 1))
    moving = step_terms(replace(inp, a_object=a), s.dt, kern.Iinv, Ib)
    held = np.asarray(inp.object_held) & (np.asarray(inp.object_mass) > 0)
    assert held.any() and not held.all()
    m_o = 3.0
    f = m_o * np.array([-1.5, 2.0, -(srbd.GRAVITY + 0.7)])
    assert inp.p_object is not None
    for k in range(N):
        if not held[k]:
            np.testing.assert_array_equal(moving.f_ext[k], 0.0)
            continue
        pc = inp.x0[srbd.POS] if k == 0 else inp.x_ref[k - 1, srbd.POS]
        np.testing.assert_allclose(moving.f_ext[k], f, rtol=0, atol=1e-12)
        np.testing.assert_allclose(
            moving.tau_ext[k], np.cross(inp.p_object[k] - pc, f), rtol=0, atol=1e-12
        )
        np.testing.assert_allclose(
            rest.f_ext[k], [0.0, 0.0, -m_o * srbd.GRAVITY], rtol=0, atol=1e-12
        )
