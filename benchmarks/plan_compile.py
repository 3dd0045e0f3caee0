"""How long planning takes: `compile_robot_plan` on generated envelope scripts.

Run: .venv/bin/python benchmarks/plan_compile.py [--n N] [--seed S] [--robot NAME]
     [--family F ...] [--strategy dynamic|quasi-static]

Draws N scripts with `locoplan.envelope.generate_suite(N, S, families, robot)` (default: 200
scripts of seed 48027 at Unitree H1's scale, the families that hold objects), compiles each
one's plan in this process as `locoplan plan`, `validate` and every simulating command do
(hand paths, reach and payload checks, a hurried turn where one is needed), and prints the
median, 90th and 99th percentile and largest compile time (s), the total, and the five
slowest scripts. A plan the compiler refuses counts too (its time is what a user waits for
the refusal). The first compile (loading the robot's model for the statics) is run once
before timing. Single-threaded: run it with the other core idle for figures that compare.
"""

from __future__ import annotations

import os

os.environ["OMP_NUM_THREADS"] = "1"  # before numpy
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse
import statistics
import time

from locoplan.envelope import generate_suite
from locoplan.plan import PlanError
from locoplan.scenario import load_scenario
from locoplan.sim.robot_plan import compile_robot_plan

HOLDING = ("transfer", "walk-carry", "side-carry", "standing-hold", "throw")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=48027)
    ap.add_argument("--robot", default="h1", help="robot name; 'hector' for the paper's")
    ap.add_argument("--family", action="append", help="only these families (repeatable)")
    ap.add_argument("--strategy", default="dynamic", choices=("dynamic", "quasi-static"))
    args = ap.parse_args()

    robot = None if args.robot == "hector" else args.robot
    scripts = generate_suite(args.n, args.seed, args.family or list(HOLDING), robot)
    scenarios = [(s.name, load_scenario(f"{s.name}.yaml", s.text)) for s in scripts]
    compile_robot_plan(scenarios[0][1], args.strategy)  # warm: model loads, caches

    times: list[tuple[float, str, str]] = []
    for name, scenario in scenarios:
        t0 = time.perf_counter()
        try:
            compile_robot_plan(scenario, args.strategy)
            outcome = "planned"
        except PlanError as exc:
            outcome = f"refused: {str(exc).splitlines()[0][:60]}"
        times.append((time.perf_counter() - t0, name, outcome))

    values = sorted(t for t, _, _ in times)

    def pct(q: float) -> float:
        return values[min(len(values) - 1, int(q * len(values)))]

    print(
        f"{len(values)} plans ({args.robot}, seed {args.seed}, {args.strategy}): "
        f"median {statistics.median(values):.3f} s, p90 {pct(0.9):.3f} s, "
        f"p99 {pct(0.99):.3f} s, max {values[-1]:.3f} s, total {sum(values):.1f} s"
    )
    for t, name, outcome in sorted(times, reverse=True)[:5]:
        print(f"  {t:7.3f} s  {name}  ({outcome})")


if __name__ == "__main__":
    main()
