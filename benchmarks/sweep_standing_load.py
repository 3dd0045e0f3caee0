"""The standing payload sweep of issue 7: scenarios/standing-load.yaml over the block's mass.

Run: OMP_NUM_THREADS=1 .venv/bin/python benchmarks/sweep_standing_load.py [--masses 0:16:1]
     [--jobs 2] [--out runs/sweep/standing-load] [--backend local|ray]

The same as `locoplan sweep scenarios/standing-load.yaml --set objects.block.mass=0:16:1`,
plus a verdict per mass read from each point's metrics JSON: a mass is *held* when the robot
did not fall, every task goal was met (`completed`: the pick lifted the block), the block is
off the table at the end (`objects.block.on` is null) after the 5 s stand, and the torques
stayed within the limits without the last-guard clip ever acting (`torque_clips` 0; a clipped
torque makes the peak ratio read exactly 1.00, so `peak_torque_ratio <= 1` alone cannot tell).
Prints the table and the largest mass held, to compare with the paper's 14 kg (82 % of the
robot's mass). Mass 0 is not a valid script (masses must be positive): it shows
up as an invalid point. Takes about (17 points x 8 s simulated) / (real-time factor x jobs).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from locoplan.batch import build_points, csv_text, parse_set, run_sweep, sweep_jobs, sweep_rows
from locoplan.batch.batch import metrics_path
from locoplan.report.sweep_plot import plot_sweep
from locoplan.scenario import load_scenario_file

SCRIPT = Path(__file__).resolve().parents[1] / "scenarios" / "standing-load.yaml"
PAPER_LIMIT_KG = 14.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--masses", default="0:16:1", help="VALUES of the mass (kg)")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--backend", default="local")
    parser.add_argument("--out", type=Path, default=Path("runs/sweep/standing-load"))
    args = parser.parse_args()

    loaded = load_scenario_file(SCRIPT)
    axes = [parse_set(f"objects.block.mass={args.masses}")]
    points = build_points(SCRIPT, loaded.text, axes)
    jobs = sweep_jobs(points, axes, loaded.scenario.name, SCRIPT, args.out)
    start = time.perf_counter()
    outcomes = run_sweep(jobs, args.backend, args.jobs)
    elapsed = time.perf_counter() - start
    rows = sweep_rows(axes, points, outcomes)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "standing-load-sweep.csv").write_text(csv_text(axes, rows))
    plot_sweep(rows, [axes[0].key], "peak_torque_ratio", args.out / "standing-load-sweep.png")

    by_label = {job.job_id: job for job in jobs}
    held_masses: list[float] = []
    print(f"{'mass kg':>8} {'fell':>5} {'fall t':>7} {'torque':>7} {'joint':>16} {'held':>5}  note")
    for point, row in zip(points, rows, strict=True):
        mass = point.values[0]
        label = f"objects.block.mass={mass}"
        if point.error is not None or label not in by_label:
            print(f"{mass:>8} {'':>5} {'':>7} {'':>7} {'':>16} {'':>5}  {point.error}")
            continue
        path = metrics_path(by_label[label])
        metrics = json.loads(path.read_text()) if path.is_file() else {}
        block = metrics.get("objects", {}).get("block", {})
        fell = bool(metrics.get("fell"))
        ratio = metrics.get("peak_torque_ratio")
        clips = int(metrics.get("torque_clips", 0))
        lifted = bool(metrics.get("completed")) and block.get("on") is None
        within = ratio is not None and ratio <= 1.0 and clips == 0
        held = lifted and within and not fell
        if held:
            held_masses.append(float(mass))
        fall_t = metrics.get("fall_time")
        notes = []
        if not metrics.get("completed"):
            notes.append("a task goal was never met (the pick did not finish)")
        if block.get("on") is not None:
            notes.append(f"block ends on the {block['on']}")
        if clips:
            notes.append(f"{clips} torque clips, {metrics.get('wbc_failures', 0)} WBC failures")
        if row["error"]:
            notes.append(str(row["error"]))
        print(
            f"{mass:>8} {('yes' if fell else 'no'):>5} "
            f"{(f'{fall_t:.2f}' if fall_t is not None else '-'):>7} "
            f"{(f'{ratio:.3f}' if ratio is not None else '-'):>7} "
            f"{metrics.get('peak_torque_joint', '-')!s:>16} {('yes' if held else 'no'):>5}  "
            f"{'; '.join(notes)}"
        )
    print(f"wall time {elapsed:.0f} s on {args.jobs} {args.backend} workers")
    print(f"CSV and plot in {args.out}")
    if held_masses:
        print(f"largest mass held: {max(held_masses):g} kg (paper: {PAPER_LIMIT_KG:g} kg)")
    else:
        print(f"no mass held (paper: {PAPER_LIMIT_KG:g} kg)")


if __name__ == "__main__":
    main()
