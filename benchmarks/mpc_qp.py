"""Benchmark of one MPC update (build + solve) at horizon 20, per backend and formulation,
and of the default path on inputs recorded from the real closed loop, before vs now.

Run: OMP_NUM_THREADS=1 .venv/bin/python benchmarks/mpc_qp.py [--updates 300] [--quick]
     OMP_NUM_THREADS=1 .venv/bin/python benchmarks/mpc_qp.py --scenario scenarios/walk-square.yaml
         [--scenario ...] [--before REV] [--rerecord]

Synthetic inputs (default mode) are recorded from a closed loop in which the SRBD itself is
the plant (17 kg, trunk inertia diag(0.17, 0.15, 0.06) or the composite one with pitch 0.59,
feet at +-0.1 m lateral, CoM 0.55 m high), the MPC re-solved every 10 ms and its first-step
wrench applied, with a small random disturbance force. Three scenarios: standing (both
feet), stepping in place (0.4 s gait, 0.05 s double support, 0.15 s swing per foot) and
standing with 5 kg held 0.3 m ahead (CoP bounds often active). Every combination then
replays the same recorded inputs in order, on a fresh controller, so solver re-use and
caches behave as in the loop. Columns: build (outside the solver: for daqp the structured
factorisation and x_u included; U and W of the least-distance form, built only when x_u
violates a bound, count as solve) and solve time, their total (wall and thread CPU time; the
CPU time is the steadier figure on a shared machine), iterations median/max, the share of
updates whose unconstrained minimiser met every bound (daqp not run) and the fallbacks.

--scenario: the task script runs closed loop in MuJoCo with the real controller; every
MpcInput of that run is recorded once into runs/ (again with --rerecord, e.g. after
controller changes) and replayed in order through a fresh MultiContactMpc with the
controller's MPC settings, now and with the locoplan package of git revision --before (in a
subprocess), printing median / p99 of one update for both and the largest relative
difference between their solutions U (--model overrides the script's model). Measured on
this 2-core machine (shared with other jobs; best of 5 replays), before = 69f8286 (numpy
build, LAPACK block factor) and now (numba kernels), median / p99 in us:

    scenario                      updates  constrained  before        now         max |dU|/|U|
    walk-square                      1732      12 %     741 / 1349    136 /  623     4e-12
    package-transfer                  461      59 %    1141 / 2072    391 / 1344     6e-12
    package-transfer (combined)       461      63 %    1152 / 1968    392 / 1030     3e-12
    stand                            1000       0 %     572 /  754    163 /  234     4e-12
    standing-load (14 kg held)        800      82 %    1769 / 2766   1093 / 1287     5e-11

A constrained update pays for U = L^-T (LAPACK trtri, 90 us at 125 variables, 240 us at 200)
and DAQP's own set-up of W (60-140 us) on top of the unconstrained one. Inside the closed
loop an update takes longer than replayed back to back: walk-square 225 / 841 us (before
885 / 1553), measured around MultiContactMpc.update in a run.
"""

from __future__ import annotations

import argparse
import hashlib
import io
import os
import pickle
import subprocess
import sys
import tarfile
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from locoplan.control import srbd
from locoplan.control.mpc import MpcInput, MpcSettings, MultiContactMpc
from locoplan.control.qp import QpSettings

ROOT = Path(__file__).resolve().parents[1]
N = 20
DT = 0.03
MASS = 17.0
INERTIA_TRUNK = np.diag([0.17, 0.15, 0.06])
INERTIA_COMPOSITE = np.diag([0.62, 0.59, 0.12])
Z_COM = 0.55
P_FEET = np.array([[0.0, 0.1, 0.0], [0.0, -0.1, 0.0]])


def standing_contact(t: np.ndarray) -> np.ndarray:
    """Both feet down at every time t (n,) -> (n, 2) bool."""
    return np.ones((t.shape[0], 2), dtype=bool)


def stepping_contact(t: np.ndarray) -> np.ndarray:
    """Step in place: period 0.4 s, 0.05 s double support, 0.15 s swing per foot."""
    ph = np.mod(t, 0.4)
    left = ~((ph >= 0.05) & (ph < 0.2))
    right = ~((ph >= 0.25) & (ph < 0.4))
    return np.stack([left, right], axis=1)


def reference_state() -> np.ndarray:
    x = np.zeros(15)
    x[srbd.POS] = [0.0, 0.0, Z_COM]
    x[srbd.GRAV] = srbd.gravity_state()
    return x


def make_input(
    t: float,
    x0: np.ndarray,
    schedule: Callable[[np.ndarray], np.ndarray],
    inertia: np.ndarray,
    object_mass: float = 0.0,
) -> MpcInput:
    """The MPC input at time t (s) for state x0 (15,) and the given contact schedule."""
    times = t + DT * np.arange(N)
    x_ref = np.tile(reference_state(), (N, 1))
    held = np.full(N, object_mass > 0.0)
    return MpcInput(
        x0=x0,
        x_ref=x_ref,
        contact=schedule(times),
        p_feet=np.tile(P_FEET, (N, 1, 1)),
        foot_yaw=np.zeros((N, 2)),
        yaw_lin=np.zeros(N),
        mass=MASS,
        inertia_body=inertia,
        object_held=held,
        object_mass=object_mass,
        p_object=np.tile([0.3, 0.0, Z_COM], (N, 1)),
        t=t,
    )


def record_inputs(
    schedule: Callable[[np.ndarray], np.ndarray],
    n_updates: int,
    inertia: np.ndarray = INERTIA_TRUNK,
    seed: int = 0,
    period: float = 0.01,
    noise: float = 1.0,
    object_mass: float = 0.0,
) -> list[MpcInput]:
    """Closed loop with the SRBD as plant; returns the MPC inputs met along the way.

    The MPC sees the state plus Gaussian noise of standard deviation ``noise`` x (0.5 deg,
    5 mm, 0.1 rad/s, 0.05 m/s) -- the size of the errors a whole-body loop leaves -- which
    makes a third to a half of the QPs have active constraints; with noise 0 almost none do.
    ``object_mass`` (kg) is held 0.3 m ahead at CoM height with the CoM reference left above
    the ankles: 5 kg needs the CoP 68 mm ahead of the ankle (toe 90 mm), so with the noise
    the CoP bounds are often active over much of the horizon; 6 kg and more fall here.
    """
    rng = np.random.default_rng(seed)
    mpc = MultiContactMpc(MpcSettings())
    x = reference_state()
    inputs: list[MpcInput] = []
    sigma = noise * np.repeat([np.radians(0.5), 0.005, 0.1, 0.05], 3)
    for i in range(n_updates):
        t = i * period
        x_meas = x.copy()
        x_meas[:12] += sigma * rng.normal(size=12)
        inp = make_input(t, x_meas, schedule, inertia, object_mass)
        inputs.append(inp)
        sol = mpc.update(inp)
        contact = schedule(np.array([t]))[0]
        u = np.concatenate([sol.U[0, 0, 0:3], sol.U[0, 1, 0:3], sol.U[0, 0, 3:5], sol.U[0, 1, 3:5]])
        cm = srbd.continuous_model(
            0.0,
            x[srbd.POS],
            P_FEET,
            np.zeros(2),
            contact,
            MASS,
            inertia,
            object_mass > 0,
            object_mass,
            np.array([0.3, 0.0, Z_COM]),
        )
        dm = srbd.discretize(cm, period)
        x = dm.A @ x + dm.B @ u + dm.d
        # Disturbance: a random push of a few newtons on the CoM over the period.
        x[srbd.VEL] += rng.normal(scale=3.0, size=3) * period / MASS
    return inputs


def time_updates(settings: MpcSettings, inputs: list[MpcInput]) -> dict[str, np.ndarray]:
    """Replay inputs through a fresh controller; per-update times (us) and counters."""
    mpc = MultiContactMpc(settings)
    mpc.update(inputs[0])  # the first update sets up caches and the solver object
    total, cpu, build, solve, iters, unc = [], [], [], [], [], []
    fallbacks = 0
    for inp in inputs:
        c0 = time.thread_time()
        t0 = time.perf_counter()
        sol = mpc.update(inp)
        total.append(time.perf_counter() - t0)
        cpu.append(time.thread_time() - c0)
        build.append(sol.build_time_s)
        solve.append(sol.solve_time_s)
        iters.append(sol.iterations)
        # daqp's least-distance path: the unconstrained minimiser met every bound.
        unc.append(sol.qp is not None and sol.qp.ok and sol.qp.iterations == 0)
        fallbacks += sol.fallback != "none"
    return {
        "total": np.array(total) * 1e6,
        "cpu": np.array(cpu) * 1e6,
        "build": np.array(build) * 1e6,
        "solve": np.array(solve) * 1e6,
        "iters": np.array(iters),
        "unconstrained": np.array(unc),
        "fallbacks": np.array([fallbacks]),
    }


def combinations(quick: bool) -> list[tuple[str, MpcSettings]]:
    """Named settings to compare; the first is the default."""
    base = MpcSettings()
    out = [("condensed daqp, least-distance form (default)", base)]
    # daqp started from the previous update's active set moved on by the elapsed steps.
    out.append(
        (
            "condensed daqp, active-set hint",
            replace(base, qp=replace(base.qp, warm_start=True)),
        )
    )
    prox = replace(base, backend="proxsuite")
    out.append(("condensed proxsuite", prox))
    out.append(
        ("condensed proxsuite, warm start", replace(prox, qp=replace(prox.qp, warm_start=True)))
    )
    pre = replace(prox.qp, scaling=False, preconditioner=True)
    out.append(("condensed proxsuite, its own preconditioner", replace(prox, qp=pre)))
    out.append(("condensed piqp", replace(base, backend="piqp")))
    if not quick:
        sparse_qp = QpSettings(eps_abs=1e-6, eps_gap_abs=1e-6, max_iter=100, eps_primal_inf=1e-9)
        out.append(
            ("sparse piqp", replace(base, formulation="sparse", backend="piqp", qp=sparse_qp))
        )
        out.append(
            (
                "sparse proxsuite",
                replace(base, formulation="sparse", backend="proxsuite", qp=sparse_qp),
            )
        )
    return out


def _fmt(a: np.ndarray) -> str:
    return f"{np.median(a):6.0f} / {np.percentile(a, 99):6.0f}"


# --- recorded closed-loop inputs, before vs now ------------------------------------------


def record_scenario(path: Path, model: str | None = None) -> dict[str, Any]:
    """Run the scenario closed loop in MuJoCo (the real controller, no log; ``model``
    overrides the script's) and return the MPC's settings and every MpcInput it met, as
    plain dicts (readable by older code)."""
    from locoplan.scenario import load_scenario_file
    from locoplan.sim.run import RunOptions, run_scenario

    settings: list[dict[str, Any]] = []
    inputs: list[dict[str, Any]] = []
    update = MultiContactMpc.update

    def recording(self: MultiContactMpc, inp: MpcInput) -> Any:
        if not settings:
            settings.append(asdict(self.settings))
        inputs.append({f.name: getattr(inp, f.name) for f in fields(inp)})
        return update(self, inp)

    loaded = load_scenario_file(path)
    MultiContactMpc.update = recording  # type: ignore[method-assign]
    try:
        with tempfile.TemporaryDirectory() as tmp:
            options = RunOptions(out_dir=Path(tmp), log=False, model=model)
            run_scenario(loaded.scenario, loaded.text, options)
    finally:
        MultiContactMpc.update = update  # type: ignore[method-assign]
    return {"settings": settings[0], "inputs": inputs}


def recorded(path: Path, again: bool, model: str | None = None) -> Path:
    """The recorded inputs of a scenario, cached in runs/ per scenario text and model
    (re-recorded with ``again``, e.g. after controller changes)."""
    digest = hashlib.sha1(path.read_bytes()).hexdigest()[:10]
    tag = f"-{model}" if model else ""
    cache = ROOT / "runs" / f"mpc-inputs-{path.stem}{tag}-{digest}.pkl"
    if again or not cache.exists():
        cache.parent.mkdir(parents=True, exist_ok=True)
        with cache.open("wb") as f:
            pickle.dump(record_scenario(path, model), f)
    return cache


def replay(cache: Path, repeat: int) -> dict[str, Any]:
    """Replay the recorded inputs in order through a fresh MultiContactMpc, ``repeat`` times
    (the replay with the lowest median is kept): per-update wall and CPU times (us),
    iterations, and the solutions U."""
    with cache.open("rb") as f:
        rec = pickle.load(f)
    st = dict(rec["settings"])
    st["qp"] = QpSettings(**st["qp"])
    if st.get("relaxed_qp") is not None:
        st["relaxed_qp"] = QpSettings(**st["relaxed_qp"])
    settings = MpcSettings(**st)
    inputs = [MpcInput(**d) for d in rec["inputs"]]
    MultiContactMpc(settings).update(inputs[0])  # compiles or loads what needs it
    best: dict[str, Any] | None = None
    for _ in range(repeat):
        mpc = MultiContactMpc(settings)
        wall, cpu, iters, Us = [], [], [], []
        for inp in inputs:
            c0 = time.thread_time()
            t0 = time.perf_counter()
            sol = mpc.update(inp)
            wall.append(time.perf_counter() - t0)
            cpu.append(time.thread_time() - c0)
            iters.append(sol.iterations)
            Us.append(sol.U)
        run = {
            "wall": (np.array(wall) * 1e6).tolist(),
            "cpu": (np.array(cpu) * 1e6).tolist(),
            "iters": iters,
            "U": np.array(Us),
        }
        if best is None or np.median(run["wall"]) < np.median(best["wall"]):
            best = run
    assert best is not None
    return best


def replay_at(rev: str, cache: Path, repeat: int) -> dict[str, Any]:
    """`replay` with the locoplan package of git revision ``rev``, in a subprocess."""
    with tempfile.TemporaryDirectory() as tmp:
        archive = subprocess.run(
            ["git", "-C", str(ROOT), "archive", rev, "locoplan"],
            check=True,
            capture_output=True,
        ).stdout
        with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
            tar.extractall(tmp, filter="data")
        out = Path(tmp) / "replay.npz"
        env = dict(os.environ, PYTHONPATH=tmp, OMP_NUM_THREADS="1")
        cmd = [sys.executable, __file__, "--replay", str(cache), str(out), str(repeat)]
        subprocess.run(cmd, check=True, env=env, cwd=tmp)
        with np.load(out) as d:
            return {k: d[k] for k in d.files}


def _replay_main(cache: str, out: str, repeat: str) -> None:
    r = replay(Path(cache), int(repeat))
    np.savez(out, wall=r["wall"], cpu=r["cpu"], iters=r["iters"], U=r["U"])


def compare_recorded(
    scenarios: list[str], before: str, repeat: int, again: bool, model: str | None
) -> None:
    rev = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", before],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    print(
        "recorded closed-loop MPC inputs (MuJoCo, the real controller), replayed in order; "
        f"one update = build + solve; times in us, median / p99 (best of {repeat} replays)"
    )
    print(
        f"{'scenario':30s} {'updates':>7s} {'constr.':>7s} {'before ' + rev:>17s}"
        f" {'now':>15s} {'now, CPU':>15s}  max |dU|/|U|"
    )
    for name in scenarios:
        path = Path(name)
        cache = recorded(path, again, model)
        now = replay(cache, repeat)
        old = replay_at(before, cache, repeat)
        U_now, U_old = np.asarray(now["U"]), np.asarray(old["U"])
        k = U_now.shape[0]
        diff = np.linalg.norm((U_now - U_old).reshape(k, -1), axis=1)
        scale = np.maximum(np.linalg.norm(U_old.reshape(k, -1), axis=1), 1e-300)
        constrained = 100.0 * float(np.mean(np.asarray(now["iters"]) > 0))
        print(
            f"{path.stem + (f' ({model})' if model else ''):30s} {k:7d} {constrained:6.0f}%"
            f" {_fmt(np.asarray(old['wall'])):>17s}"
            f" {_fmt(np.asarray(now['wall']))} {_fmt(np.asarray(now['cpu']))}"
            f"  {float(np.max(diff / scale)):9.1e}"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--updates", type=int, default=300)
    ap.add_argument("--quick", action="store_true", help="skip the slow sparse formulations")
    ap.add_argument("--composite", action="store_true", help="composite inertia (pitch 0.59)")
    ap.add_argument("--noise", type=float, default=1.0, help="state noise level (see record)")
    ap.add_argument("--repeat", type=int, default=3, help="replays per combination (best kept)")
    ap.add_argument(
        "--only", action="append", default=[], help="run combinations whose name contains this"
    )
    ap.add_argument(
        "--scenario",
        action="append",
        default=[],
        help="instead: replay the MPC inputs of this task script's closed loop (recorded once "
        "into runs/), now and at --before",
    )
    ap.add_argument("--before", default="69f8286", help="git revision to compare against")
    ap.add_argument("--rerecord", action="store_true", help="record the scenarios again")
    ap.add_argument("--model", help="with --scenario: external-force | combined (the script's)")
    if len(sys.argv) == 5 and sys.argv[1] == "--replay":  # the subprocess of replay_at
        _replay_main(*sys.argv[2:])
        return
    args = ap.parse_args()
    if os.environ.get("OMP_NUM_THREADS") != "1":
        print("warning: set OMP_NUM_THREADS=1 for single-core figures")
    if args.scenario:
        compare_recorded(args.scenario, args.before, args.repeat, args.rerecord, args.model)
        return
    inertia = INERTIA_COMPOSITE if args.composite else INERTIA_TRUNK
    scenarios = {
        "standing": record_inputs(standing_contact, args.updates, inertia, noise=args.noise),
        "stepping": record_inputs(stepping_contact, args.updates, inertia, noise=args.noise),
        "stand+5kg": record_inputs(
            standing_contact, args.updates, inertia, noise=args.noise, object_mass=5.0
        ),
    }
    print(
        f"horizon {N}, dt {DT}, {args.updates} updates per scenario, noise {args.noise}, "
        f"inertia diag{tuple(np.diag(inertia))}; times in us, median / p99"
    )
    header = f"{'combination':44s} {'scenario':9s} {'build':>15s} {'solve':>15s} {'total':>15s}"
    print(header + f" {'total CPU':>15s}  iters  unc.  fallb.")
    for name, settings in combinations(args.quick):
        if args.only and not any(o in name for o in args.only):
            continue
        for scen, inputs in scenarios.items():
            # Other processes share the cores: keep the replay with the lowest median.
            runs = [time_updates(settings, inputs) for _ in range(args.repeat)]
            r = min(runs, key=lambda x: float(np.median(x["total"])))
            print(
                f"{name:44s} {scen:9s} {_fmt(r['build'])} {_fmt(r['solve'])} {_fmt(r['total'])}"
                f" {_fmt(r['cpu'])}  {np.median(r['iters']):2.0f}/{r['iters'].max():2d}"
                f" {100 * r['unconstrained'].mean():5.1f}% {int(r['fallbacks'][0]):3d}"
            )


if __name__ == "__main__":
    main()
