"""Closed-loop speed on scenarios/walk-square.yaml (17.3 s of walking and turning).

Prints the real-time factor, the MPC update and WBC tick times (median, p99; QP build
included) and where a physics step's wall time goes (physics, dynamics terms, MPC, WBC,
logging, the rest; medians over the repeats). Run on a quiet machine, one core:

    OMP_NUM_THREADS=1 .venv/bin/python benchmarks/closed_loop.py [SCENARIO] [--repeat N]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
from pathlib import Path

import numpy as np

from locoplan.scenario import load_scenario_file
from locoplan.sim.run import RunOptions, run_scenario

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenario", nargs="?", default=str(ROOT / "scenarios/walk-square.yaml"))
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--no-log", action="store_true", help="Run without the MCAP log.")
    parser.add_argument("--qp", default="daqp", help="QP backend: daqp | proxsuite | piqp")
    args = parser.parse_args()
    loaded = load_scenario_file(args.scenario)
    rtfs = []
    shares: dict[str, list[float]] = {}  # part -> us per physics step, one per repeat
    for _ in range(args.repeat):
        with tempfile.TemporaryDirectory() as tmp:
            result = run_scenario(
                loaded.scenario,
                loaded.text,
                RunOptions(out_dir=Path(tmp), log=not args.no_log, qp_backend=args.qp),
            )
        rec = result.record
        rtfs.append(rec.sim_time / rec.wall_time)
        split = dict(rec.tick_split_s)
        split["other"] = rec.wall_time - sum(split.values())
        split["total"] = rec.wall_time
        for k, v in split.items():
            shares.setdefault(k, []).append(v / rec.n_ticks * 1e6)
    m = result.metrics
    mpc = np.asarray(rec.mpc_times_s) * 1e3
    wbc = np.asarray(rec.wbc_times_s) * 1e3
    steps = rec.n_ticks
    print(
        f"scenario          {m['scenario']} ({rec.sim_time:.1f} s simulated, {steps} physics steps)"
    )
    print(f"fell              {m['fell']}")
    runs = f"median of {len(rtfs)}: " + " ".join(f"{r:.2f}" for r in sorted(rtfs))
    print(f"real-time factor  {statistics.median(rtfs):.2f}x ({runs})")
    for name, a in (("MPC update", mpc), ("WBC tick", wbc)):
        med, p99 = np.median(a), np.percentile(a, 99)
        print(f"{name:<11} ms    median {med:.3f}  p99 {p99:.3f}  (n={a.size}, last run)")
    # "logging" is everything written to the MCAP log (the MPC solution at each update, the
    # samples every 10 ms, the 3D scene); "other" is what no part accounts for.
    total = statistics.median(shares.pop("total"))
    print(f"wall time per physics step (us, median of {len(rtfs)}) and share of {total:.1f} us:")
    for part, per_run in shares.items():
        us = statistics.median(per_run)
        print(f"  {part:<9} {us:8.1f} us  {100 * us / total:5.1f} %")


if __name__ == "__main__":
    main()
