"""One WBC tick (task stacking, prioritised projection, QP build, QP solve) on recorded inputs.

Records the whole-body controller's inputs from a closed-loop run of a scenario (default:
the first seconds of scenarios/walk-square.yaml, stepping, turning and contact switches), or
loads a recording, then replays every tick through the controller's path (`wbc_kernels.stack_tasks`,
`prioritized_rows`, `WholeBodyQp.solve_arrays`) and prints median / p99 per piece (best of
--repeat passes per tick, so that other processes on the machine count less) and how far the
torques are from the recorded ones. --cold runs unrelated numpy work before each tick, as
MuJoCo, the MPC and the logger do in the closed loop (it evicts caches: the closed loop's
"WBC tick" also includes the controller's call site, plan lookups and pinocchio accessors):

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/wbc_tick.py [--seconds 6] [--repeat 5] [--cold]
    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/wbc_tick.py --inputs tests/data/wbc_ticks.npz
    .venv/bin/python benchmarks/wbc_tick.py --seconds 8 --every 40 --save tests/data/wbc_ticks.npz
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

import locoplan.control.controller as controller_module
from locoplan.control.tasks import TaskGains
from locoplan.control.wbc import WholeBodyQp, prioritized_rows
from locoplan.control.wbc_kernels import stack_tasks
from locoplan.plan import compile_plan
from locoplan.robot.description import load_robot_description
from locoplan.scenario import load_scenario_file
from locoplan.sim.loop import ClosedLoop
from locoplan.sim.run import RunOptions, controller_settings, scene_for

ROOT = Path(__file__).resolve().parents[1]
GAIN_FIELDS = TaskGains.__slots__


def record(scenario_path: str, seconds: float, every: int) -> dict[str, np.ndarray]:
    """Run the scenario closed loop for `seconds` and keep every `every`-th WBC tick's inputs
    and every tick at a contact switch (arrays stacked over ticks; see `kernel_inputs` for how
    they map back)."""
    loaded = load_scenario_file(scenario_path)
    sc = loaded.scenario
    plan = compile_plan(sc, None)
    desc = load_robot_description(sc.robot)
    settings = controller_settings(sc, RunOptions(log=False))
    rows: list[dict[str, Any]] = []
    current: dict[str, Any] = {}
    count = [0]
    prev_stance: list[tuple[bool, ...]] = [()]
    orig_stack = controller_module.stack_tasks
    orig_solve = WholeBodyQp.solve_arrays

    def rec_stack(gains: np.ndarray, *args: Any) -> Any:
        (q, v, R, omega, p_des, v_des, yaw_des, pitch_des, yaw_rate_des) = args[:9]
        (J_base, dJv_base, stance) = args[9:12]
        (J_feet, dJv_feet, v_feet, p_feet, R_feet, n_swing, sw, sw_yaw) = args[12:20]
        (J_hands, dJv_hands, hand_acc) = args[20:]
        current.clear()
        packed = np.asarray(gains, dtype=float)
        sizes = [3, 3, 3, 3, 1, 1, 1, 1]
        split = np.split(packed, np.cumsum(sizes)[:-1])
        current.update(
            gains=list(split),
            q=q.copy(),
            v=v.copy(),
            R=R.copy(),
            omega=omega.copy(),
            p_des=p_des.copy(),
            v_des=v_des.copy(),
            yaw_des=yaw_des,
            pitch_des=pitch_des,
            yaw_rate_des=yaw_rate_des,
            J_base=J_base.copy(),
            dJv_base=dJv_base.copy(),
            stance=np.array(stance, dtype=bool),
            J_feet=J_feet.copy(),
            dJv_feet=dJv_feet.copy(),
            v_feet=v_feet.copy(),
            p_feet=p_feet.copy(),
            R_feet=R_feet.copy(),
            n_swing=n_swing,
            swing_pva=sw.copy(),
            swing_yaw=sw_yaw.copy(),
            J_hands=J_hands.copy(),
            dJv_hands=dJv_hands.copy(),
            hand_acc=hand_acc.copy(),
        )
        return orig_stack(gains, *args)

    def rec_solve(
        self: WholeBodyQp,
        M: np.ndarray,
        h: np.ndarray,
        qdd_cmd: np.ndarray,
        Jc: np.ndarray,
        yaws: np.ndarray,
        w5: np.ndarray,
        tau_ext: np.ndarray,
    ) -> Any:
        out = orig_solve(self, M, h, qdd_cmd, Jc, yaws, w5, tau_ext)
        count[0] += 1
        st = tuple(bool(x) for x in current.get("stance", ()))
        switched = st != prev_stance[0]
        prev_stance[0] = st
        if current and ((count[0] - 1) % every == 0 or switched):
            yaw = np.zeros(2)
            w5_feet = np.zeros((2, 5))
            ks = np.flatnonzero(current["stance"])
            for i, k in enumerate(ks):
                yaw[k] = yaws[i]
                w5_feet[k] = w5[5 * i : 5 * i + 5]
            row = dict(current)
            row.update(
                M=M.copy(),
                h=h.copy(),
                qdd_cmd=qdd_cmd.copy(),
                contact_yaw=yaw,
                contact_w5=w5_feet,
                tau_ext=tau_ext.copy(),
                tau=out.tau.copy(),
                wbc_ok=out.ok,
            )
            rows.append(row)
        return out

    controller_module.stack_tasks = rec_stack  # type: ignore[assignment]
    WholeBodyQp.solve_arrays = rec_solve  # type: ignore[method-assign]
    try:
        start = sc.robot_start
        loop = ClosedLoop(
            scene_for(sc, desc),
            desc,
            plan,
            settings,
            start_xy=(start.position[0], start.position[1]),
            start_yaw=math.radians(start.yaw),
        )
        loop.run(min(seconds, plan.t_end))
    finally:
        controller_module.stack_tasks = orig_stack
        WholeBodyQp.solve_arrays = orig_solve  # type: ignore[method-assign]
    out: dict[str, np.ndarray] = {}
    for key in rows[0]:
        if key == "gains":
            for f, val in zip(GAIN_FIELDS, rows[0]["gains"], strict=True):
                out[f"gain_{f}"] = np.asarray(val, dtype=float)
        else:
            out[key] = np.array([r[key] for r in rows])
    out["tau_limits"] = np.asarray(desc.torque_limits, dtype=float)
    return out


def recorded_gains(rec: dict[str, np.ndarray]) -> TaskGains:
    """The task gains of a recording (the same for every tick)."""
    return TaskGains(
        *(
            tuple(float(x) for x in rec[f"gain_{f}"])
            if rec[f"gain_{f}"].size > 1
            else float(rec[f"gain_{f}"][0])
            for f in GAIN_FIELDS
        )
    )


def _other_work(rng: np.random.Generator) -> None:
    """Unrelated numpy and Python work, as MuJoCo, the MPC and the logger do between two WBC
    ticks in the closed loop: it evicts caches and branch history."""
    for _ in range(3):
        A = rng.random((60, 60))
        np.linalg.cholesky(A @ A.T + np.eye(60))
        sum(i * 0.5 for i in range(300))
        _ = {str(i): i for i in range(100)}


def kernel_inputs(rec: dict[str, np.ndarray], i: int) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
    """Tick i as the controller passes it: (`stack_tasks` arguments, `solve_arrays` arguments
    after qdd_cmd, i.e. M, h, Jc, yaws, w5, tau_ext)."""
    gains = recorded_gains(rec).packed()
    stance = rec["stance"][i]
    kargs = (
        gains,
        rec["q"][i],
        rec["v"][i],
        rec["R"][i],
        rec["omega"][i],
        rec["p_des"][i],
        rec["v_des"][i],
        float(rec["yaw_des"][i]),
        float(rec["pitch_des"][i]) if "pitch_des" in rec else 0.0,
        float(rec["yaw_rate_des"][i]),
        rec["J_base"][i],
        rec["dJv_base"][i],
        np.array(stance, dtype=np.bool_),
        rec["J_feet"][i],
        rec["dJv_feet"][i],
        rec["v_feet"][i],
        rec["p_feet"][i],
        rec["R_feet"][i],
        int(rec["n_swing"][i]),
        rec["swing_pva"][i],
        rec["swing_yaw"][i],
        rec["J_hands"][i],
        rec["dJv_hands"][i],
        rec["hand_acc"][i],
    )
    idx = np.flatnonzero(stance)
    qargs = (
        rec["M"][i],
        rec["h"][i],
        rec["J_feet"][i][idx].reshape(-1, rec["J_feet"].shape[-1]),
        rec["contact_yaw"][i][idx],
        rec["contact_w5"][i][idx].ravel(),
        rec["tau_ext"][i],
    )
    return kargs, qargs


def _other_work(rng: np.random.Generator) -> None:
    """Unrelated numpy and Python work, as MuJoCo, the MPC and the logger do between two WBC
    ticks in the closed loop: it evicts caches and branch history."""
    for _ in range(3):
        A = rng.random((60, 60))
        np.linalg.cholesky(A @ A.T + np.eye(60))
        sum(i * 0.5 for i in range(300))
        _ = {str(i): i for i in range(100)}


def replay(rec: dict[str, np.ndarray], repeat: int, cold: bool) -> dict[str, np.ndarray]:
    """Per-tick times (s) of each piece, best of `repeat`, and the torque error (N m), on the
    controller's path: `stack_tasks`, `prioritized_rows`, `WholeBodyQp.solve_arrays` (QP
    build, then DAQP only when a bound binds). With `cold`, `_other_work` runs before every
    timed call."""
    n = rec["q"].shape[0]
    wbc = WholeBodyQp(rec["tau_limits"])
    rng = np.random.default_rng(0)
    keys = ("tasks", "projection", "qp_build", "qp_solve", "total")
    res: dict[str, list[float]] = {k: [] for k in (*keys, "tau_err")}
    for i in range(n):
        kargs, (M, h, Jc, yaws, w5, tau_ext) = kernel_inputs(rec, i)
        best = dict.fromkeys(keys, math.inf)
        out = None
        for _ in range(repeat):
            if cold:
                _other_work(rng)
            t0 = time.perf_counter()
            J, b, a, ends = stack_tasks(*kargs)
            t1 = time.perf_counter()
            qdd = prioritized_rows(J, a - b, ends)
            t2 = time.perf_counter()
            out = wbc.solve_arrays(M, h, qdd, Jc, yaws, w5, tau_ext)
            t3 = time.perf_counter()
            for key, val in (
                ("tasks", t1 - t0),
                ("projection", t2 - t1),
                ("qp_build", out.build_time_s),
                ("qp_solve", out.solve_time_s),
                ("total", t3 - t0),
            ):
                best[key] = min(best[key], val)
        assert out is not None
        for key, val in best.items():
            res[key].append(val)
        res["tau_err"].append(float(np.max(np.abs(out.tau - rec["tau"][i]))))
    return {k: np.asarray(v) for k, v in res.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default=str(ROOT / "scenarios/walk-square.yaml"))
    parser.add_argument("--seconds", type=float, default=6.0, help="simulated time to record")
    parser.add_argument("--every", type=int, default=1, help="keep every n-th tick")
    parser.add_argument("--inputs", help="replay this recording (.npz) instead of recording")
    parser.add_argument("--save", help="save the recording (.npz) here")
    parser.add_argument("--repeat", type=int, default=5, help="best of N per tick and piece")
    parser.add_argument(
        "--cold", action="store_true", help="run unrelated work before each tick (as in the loop)"
    )
    args = parser.parse_args()
    if args.inputs:
        with np.load(args.inputs, allow_pickle=False) as f:
            rec = {k: f[k] for k in f.files}
    else:
        rec = record(args.scenario, args.seconds, args.every)
        if args.save:
            np.savez_compressed(args.save, **rec)  # type: ignore[arg-type]
    n = rec["q"].shape[0]
    n_st = rec["stance"].sum(axis=1)
    print(
        f"{n} ticks: {int(np.sum(n_st == 2))} double support, {int(np.sum(n_st == 1))} single, "
        f"{int(np.sum(n_st == 0))} none"
    )
    res = replay(rec, args.repeat, args.cold)
    for k in ("tasks", "projection", "qp_build", "qp_solve", "total"):
        a = res[k] * 1e6
        print(f"{k:<11} us  median {np.median(a):7.1f}  p99 {np.percentile(a, 99):7.1f}")
    err = res["tau_err"]
    print(f"torque vs recorded  max {np.max(err):.2e} N m  median {np.median(err):.2e} N m")


if __name__ == "__main__":
    main()
