"""Cost of writing a locoplan MCAP log: per call, per simulated second, and what a SIGKILL loses.

Run: OMP_NUM_THREADS=1 .venv/bin/python benchmarks/log_write.py [--calls N] [--kill-trials K]

1. Per-call wall time (microseconds) of each RunLogWriter method with payloads of the size
   the closed loop produces (20 links, 16 joints, an MPC plan of horizon 10 with 4 contacts,
   a WBC output, the robot's 70 scene entities): the median of the call itself, and the mean
   including the encoding, which the writer does in batches of 256 messages and at flushes.
   Building the inputs (Transform values, dicts) is timed separately where that matters.
2. File size per simulated second for realistic mixes, flushing once per simulated second
   (about once per wall second at a real-time factor near 1).
3. Optionally, a writer subprocess logging at about real time is SIGKILLed at a random moment
   K times; reports how much wall time before the kill the surviving messages reach.
"""

from __future__ import annotations

import argparse
import os
import random
import signal
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from locoplan.log import RunLogWriter, Transform, force_arrow, read_log, sphere
from locoplan.log.scene import BROWN, box, prepare_scene

N_LINKS = 20
N_JOINTS = 16
JOINTS = [f"joint_{i}" for i in range(N_JOINTS)]
LINKS = [f"link_{i}" for i in range(N_LINKS)]
RNG = np.random.default_rng(0)


def _transforms() -> list[Transform]:
    pos = RNG.normal(size=(N_LINKS, 3))
    quat = _unit_quats()
    return [Transform("world", LINKS[i], pos[i], quat[i]) for i in range(N_LINKS)]


def _unit_quats() -> np.ndarray:
    quat = RNG.normal(size=(N_LINKS, 4))
    return quat / np.linalg.norm(quat, axis=1, keepdims=True)


def _mpc_payload() -> dict[str, Any]:
    return {
        "ok": True,
        "status": "solved",
        "solve_ms": 1.4,
        "iterations": 5,
        "forces_world": RNG.normal(size=(10, 4, 3)),
        "predicted_com": RNG.normal(size=(10, 3)),
        "predicted_yaw": RNG.normal(size=10),
    }


def _wbc_payload() -> dict[str, Any]:
    return {
        "ok": True,
        "solve_ms": 0.3,
        "tau": RNG.normal(size=N_JOINTS),
        "qdd": RNG.normal(size=N_JOINTS + 6),
        "contact_forces": RNG.normal(size=(4, 3)),
    }


def _contacts_payload() -> dict[str, Any]:
    return {"stance": [True, False, True, False], "force_world": RNG.normal(size=(4, 3))}


def _scene_items() -> list[Any]:
    items: list[Any] = [
        force_arrow(f"f{i}", RNG.normal(size=3), RNG.normal(size=3) * 50) for i in range(4)
    ]
    items.append(box("package", [0.5, 0.0, 0.6], [0.2, 0.2, 0.2], color=BROWN))
    items.append(sphere("com", [0.0, 0.0, 0.55], 0.05))
    return items


def time_calls(
    fn: Callable[[int], object], calls: int, flush: Callable[[], None]
) -> tuple[float, float]:
    """Per-call cost (us) of `fn(i)` over `calls` calls, after 50 warm-up calls: the median of
    the call alone and the mean including the encoding, which the writer does in batches
    (every 256 messages and at each flush: the timed loop ends with one `flush`)."""
    for i in range(50):
        fn(i)
    flush()
    samples = np.empty(calls)
    start = time.perf_counter_ns()
    for i in range(calls):
        t0 = time.perf_counter_ns()
        fn(i + 50)
        samples[i] = time.perf_counter_ns() - t0
    flush()
    mean = (time.perf_counter_ns() - start) / calls
    return float(np.median(samples)) / 1e3, mean / 1e3


def per_call(calls: int, directory: Path) -> None:
    print(f"Per-call cost, {calls} calls each (us: median of the call / mean incl. encoding):")
    with RunLogWriter(directory / "calls.mcap", scenario_name="bench", scenario_text="") as w:
        tfs = _transforms()
        pos = RNG.normal(size=(N_LINKS, 3))
        quat = _unit_quats()
        q, v, tau = (RNG.normal(size=N_JOINTS) for _ in range(3))
        mpc, wbc, contacts = _mpc_payload(), _wbc_payload(), _contacts_payload()
        items = _scene_items()
        robot = prepare_scene(
            [box(f"link{k}/geom", RNG.normal(size=3), [0.05, 0.05, 0.2]) for k in range(70)]
        )
        cases: list[tuple[str, Callable[[int], object]]] = [
            (
                f"Transform() x{N_LINKS} from numpy (build only)",
                lambda i: (
                    [Transform("world", LINKS[k], pos[k], quat[k]) for k in range(N_LINKS)] and None
                ),
            ),
            (
                f"frame_transforms, {N_LINKS} prebuilt transforms",
                lambda i: w.frame_transforms(i * 1e-2, tfs),
            ),
            (
                f"frame_transforms incl. building {N_LINKS} Transforms",
                lambda i: w.frame_transforms(
                    i * 1e-2,
                    [Transform("world", LINKS[k], pos[k], quat[k]) for k in range(N_LINKS)],
                ),
            ),
            (
                f"frame_transforms_arrays, {N_LINKS} links from (n,3)/(n,4)",
                lambda i: w.frame_transforms_arrays(i * 1e-2, "world", LINKS, pos, quat),
            ),
            (
                f"joint_states, {N_JOINTS} joints (q, v, tau)",
                lambda i: w.joint_states(i * 1e-3, JOINTS, q, v, tau),
            ),
            ("json /mpc/plan (10x4x3 forces + 10x3 CoM)", lambda i: w.json("/mpc/plan", i, mpc)),
            ("json /wbc (tau, qdd, forces)", lambda i: w.json("/wbc", i * 1e-2, wbc)),
            ("json /contact (4 flags + 4x3)", lambda i: w.json("/contact", i * 1e-2, contacts)),
            ("json small (2 scalars)", lambda i: w.json("/small", i, {"a": 1.0, "ok": True})),
            ("event", lambda i: w.event(i * 1e-2, "grasp", object="package")),
            ("scene, 4 force arrows + box + sphere", lambda i: w.scene("/scene", i, items)),
            (
                "scene, 70 boxes prepared once (robot geometry)",
                lambda i: w.scene("/scene/robot", i * 1e-2, robot),
            ),
            (
                "scene incl. building 4 arrows + box + sphere",
                lambda i: w.scene("/scene2", i * 1e-2, _scene_items()),
            ),
            ("flush() alone", lambda i: w.flush()),
        ]
        for name, fn in cases:
            med, mean = time_calls(fn, calls, w.flush)
            print(f"  {name:<52} {med:8.1f} {mean:8.1f}")
    with RunLogWriter(
        directory / "calls6.mcap", scenario_name="bench", scenario_text="", json_decimals=6
    ) as w6:
        for name, fn in [
            ("json /mpc/plan, json_decimals=6", lambda i: w6.json("/mpc/plan", i, mpc)),
            ("json /wbc, json_decimals=6", lambda i: w6.json("/wbc", i * 1e-2, wbc)),
        ]:
            med, mean = time_calls(fn, calls, w6.flush)
            print(f"  {name:<52} {med:8.1f} {mean:8.1f}")


def size_per_second(directory: Path, sim_seconds: float) -> None:
    print(f"\nFile size per simulated second ({sim_seconds:.0f} s simulated, flush every 1 s):")
    mixes = {
        "joint states 1 kHz + tf 100 Hz + JSON 100 Hz + scene 100 Hz": (1, 10, 10, 10),
        "the same with json_decimals=6": (1, 10, 10, 10),
        "joint states 100 Hz + tf 100 Hz + JSON 100 Hz + scene 100 Hz": (10, 10, 10, 10),
        "joint states 100 Hz + tf 100 Hz + JSON 100 Hz, no scene": (10, 10, 10, 0),
        "joint states 1 kHz only": (1, 0, 0, 0),
        "tf 100 Hz only (20 links)": (0, 10, 0, 0),
        "controller JSON 100 Hz only (mpc + wbc + contact)": (0, 0, 10, 0),
        "joint states 1 kHz + tf 1 kHz + JSON 100 Hz": (1, 1, 10, 0),
    }
    ticks = int(sim_seconds * 1000)
    q, v, tau = (RNG.normal(size=N_JOINTS) for _ in range(3))
    for name, (every_js, every_tf, every_json, every_scene) in mixes.items():
        path = directory / "mix.mcap"
        wall0 = time.perf_counter()
        with RunLogWriter(
            path,
            scenario_name="bench",
            scenario_text="",
            flush_interval_s=1e9,
            json_decimals=6 if "decimals" in name else None,
        ) as w:
            for k in range(ticks):
                t = k * 1e-3
                # Plausible signals: smooth joint motion plus noise, so compression is realistic.
                q = q + 1e-3 * RNG.normal(size=N_JOINTS)
                if every_js and k % every_js == 0:
                    w.joint_states(t, JOINTS, q, v + RNG.normal(size=N_JOINTS), tau)
                if every_tf and k % every_tf == 0:
                    w.frame_transforms_arrays(
                        t, "world", LINKS, RNG.normal(size=(N_LINKS, 3)), _unit_quats()
                    )
                if every_json and k % every_json == 0:
                    w.json("/mpc/plan", t, _mpc_payload())
                    w.json("/wbc", t, _wbc_payload())
                    w.json("/contact", t, _contacts_payload())
                if every_scene and k % every_scene == 0:
                    w.scene("/scene/contacts", t, _scene_items())
                if k % 1000 == 999:
                    w.flush()
        wall = time.perf_counter() - wall0
        size = path.stat().st_size
        print(
            f"  {name:<62} {size / sim_seconds / 2**20:6.3f} MiB/s"
            f"   (writing took {wall / sim_seconds * 1e3:5.0f} ms per simulated s)"
        )


_KILL_CHILD = textwrap.dedent(
    """
    import sys, time
    import numpy as np
    from locoplan.log import RunLogWriter
    q = np.zeros(16)
    names = [f"j{i}" for i in range(16)]
    w = RunLogWriter(sys.argv[1], scenario_name="kill", scenario_text="", flush_interval_s=1.0)
    t0 = time.monotonic()
    k = 0
    while True:  # about real time: one 1 ms tick per 1 ms of wall time
        t = k * 1e-3
        w.joint_states(t, names, q, q, q)
        if k % 10 == 0:
            w.json("/wall", t, {"wall": time.monotonic()})
        k += 1
        sleep = t0 + k * 1e-3 - time.monotonic()
        if sleep > 0:
            time.sleep(sleep)
    """
)


def kill_trials(directory: Path, trials: int) -> None:
    print(f"\nSIGKILL at a random moment 1.5-3.3 s into a run at ~real time, {trials} trials:")
    losses = []
    for k in range(trials):
        path = directory / f"kill{k}.mcap"
        proc = subprocess.Popen([sys.executable, "-c", _KILL_CHILD, str(path)])
        time.sleep(1.5)  # imports and the first writes
        time.sleep(random.uniform(0.0, 1.8))
        killed_at = time.monotonic()  # CLOCK_MONOTONIC is shared by processes on Linux
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        log = read_log(path)
        last = max((msg["wall"] for _, msg in log.messages("/wall")), default=float("nan"))
        losses.append(killed_at - last)
        print(f"  trial {k}: complete={log.complete} lost {killed_at - last:5.2f} s of wall time")
    print(f"  lost: median {statistics.median(losses):.2f} s, max {max(losses):.2f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=3000)
    parser.add_argument("--sim-seconds", type=float, default=10.0)
    parser.add_argument("--kill-trials", type=int, default=0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        directory = Path(tmp)
        per_call(args.calls, directory)
        size_per_second(directory, args.sim_seconds)
        if args.kill_trials:
            kill_trials(directory, args.kill_trials)


if __name__ == "__main__":
    main()
