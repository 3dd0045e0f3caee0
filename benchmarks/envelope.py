"""Issue 12's envelope benchmark: generated task scripts, run closed loop, counted per family.

Run: .venv/bin/python benchmarks/envelope.py --n N --seed S [--family F ...]
     [--robot NAME] [--strategy dynamic|quasi-static|both] [--jobs J] [--out DIR]
     [--json PATH] [--timeout SECONDS]

Draws N scripts with `locoplan.envelope.generate_suite(N, S, families, robot)` (the families
mixed as issue 12's 80-script sample was; `--robot NAME`: the envelope at that robot's scale,
`locoplan.envelope.ranges.envelope_ranges`, its scripts saying `robot: NAME`; default HECTOR's
table as written), writes each to DIR/scripts/<family>/<name>.yaml (and, for
the quasi-static strategy, the same script with `strategy: quasi-static` to
DIR/scripts-quasi-static/<family>/<name>.yaml, so that `locoplan run PATH` reproduces either
run as it was), validates them all with `prepare_batch` and runs the valid ones with
`run_batch` on J workers (no cache; OMP_NUM_THREADS=1 in every worker; MCAP logs and metrics
under DIR/runs/). It prints, per family and strategy:

- succeeded: ran and every expectation held (no fall, peak torque ratio <= 1.0, objects
  placed where expected);
- refused: rejected before simulating. By validation (`prepare_batch`), or by the planner in
  the worker ("cannot plan"); grouped by the key of the lead's feasibility messages,
  `infeasible (<reason>): ...`, else `invalid` (or `plan`);
- failed: ran and broke an expectation or the run itself, by cause: `fell`, `not placed`
  (an expected `placed` did not hold), `torque` (peak torque ratio above the limit),
  `missed grasp` (the hands never reached the object), `not lifted` (gripped but never off
  its support: a standing hold put "back" would otherwise pass), `error` (solver failure,
  simulator instability, crashed or timed-out worker, internal error), `other`;

then the totals, the wall time, the median real-time factor of the runs, and every refused
or failed script with its one-line cause and the command that reruns it. `--json` writes the
same machine-readably.
"""

from __future__ import annotations

import os

os.environ["OMP_NUM_THREADS"] = "1"  # before numpy: the workers inherit it
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import argparse
import json
import re
import shutil
import statistics
import sys
import time
from collections import Counter
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from locoplan.batch import BatchResult, Job, Outcome, prepare_batch, run_batch
from locoplan.envelope import FAMILIES, GeneratedScript, generate_suite

STRATEGIES = ("dynamic", "quasi-static")
_FOLDERS = {"dynamic": "scripts", "quasi-static": "scripts-quasi-static"}
_INFEASIBLE = re.compile(r"infeasible \(([^)]+)\):")


@dataclass(slots=True)
class Verdict:
    """How one script ended, for the report."""

    path: str
    family: str
    strategy: str
    status: str  # succeeded | refused | failed
    reason: str = ""  # refusal reason or failure cause
    message: str = ""
    real_time_factor: float | None = None
    wall_time: float = 0.0

    @property
    def rerun(self) -> str:
        return f"locoplan run {self.path}"


@dataclass(slots=True)
class Group:
    """Counts of one family and strategy."""

    family: str
    strategy: str
    total: int = 0
    succeeded: int = 0
    refused: Counter[str] = field(default_factory=Counter)
    failed: Counter[str] = field(default_factory=Counter)
    rtf: list[float] = field(default_factory=list)

    def add(self, v: Verdict) -> None:
        self.total += 1
        if v.status == "succeeded":
            self.succeeded += 1
        elif v.status == "refused":
            self.refused[v.reason] += 1
        else:
            self.failed[v.reason] += 1
        if v.real_time_factor is not None:
            self.rtf.append(v.real_time_factor)

    def as_json(self) -> dict[str, Any]:
        return {
            "family": self.family,
            "strategy": self.strategy,
            "total": self.total,
            "succeeded": self.succeeded,
            "refused": dict(self.refused),
            "failed": dict(self.failed),
            "median_real_time_factor": _median(self.rtf),
        }


def _median(values: list[float]) -> float | None:
    return round(statistics.median(values), 3) if values else None


def refusal_reason(text: str) -> str:
    """The key of the first `infeasible (<key>):` in a refusal's text, else `invalid`."""
    m = _INFEASIBLE.search(text)
    return m.group(1).strip() if m else "invalid"


def failure_cause(outcome: Outcome) -> str:
    """One cause for a failed or broken run, most telling first: fell, not placed, torque,
    missed grasp, not lifted, error, other."""
    if outcome.status == "error" or outcome.metrics is None:
        return "error"
    metrics = outcome.metrics
    results = metrics.get("expectations", {})
    failed = [key for key, r in results.items() if not r.get("ok", True)]
    if metrics.get("fell") or "no_fall" in failed:
        return "fell"
    if any(key.startswith("placed.") for key in failed):
        return "not placed"
    if "max_torque_ratio" in failed or (metrics.get("peak_torque_ratio") or 0.0) > 1.0:
        return "torque"
    picks = [str(results[key].get("value", "")) for key in failed if key.startswith("pick.")]
    if picks:
        return "missed grasp" if any("hands" in v for v in picks) else "not lifted"
    return "other"


def refused_by_planner(outcome: Outcome) -> bool:
    """Whether a run was refused by the plan compiler before simulating (the batch reports
    it as an error whose message starts "cannot plan")."""
    return outcome.status == "error" and outcome.message.startswith("cannot plan")


def verdict(result: BatchResult, family: str, strategy: str) -> Verdict:
    """Classify one batch result (see the module docstring)."""
    case, outcome = result.case, result.outcome
    path = case.case_id
    if case.invalid is not None:
        text = outcome.detail or outcome.message
        return Verdict(path, family, strategy, "refused", refusal_reason(text), outcome.message)
    metrics = outcome.metrics or {}
    rtf = metrics.get("real_time_factor")
    rtf = float(rtf) if isinstance(rtf, int | float) and rtf > 0 else None
    wall = outcome.wall_time
    if outcome.status == "passed":
        return Verdict(path, family, strategy, "succeeded", "", "", rtf, wall)
    if refused_by_planner(outcome):
        m = _INFEASIBLE.search(outcome.message)
        reason = m.group(1).strip() if m else "plan"
        return Verdict(path, family, strategy, "refused", reason, outcome.message, None, wall)
    message = outcome.message or "; ".join(outcome.failures)
    return Verdict(path, family, strategy, "failed", failure_cause(outcome), message, rtf, wall)


def write_scripts(
    scripts: list[GeneratedScript], out: Path, strategies: tuple[str, ...]
) -> dict[Path, tuple[str, str]]:
    """Write every script once per strategy; return path -> (family, strategy)."""
    where: dict[Path, tuple[str, str]] = {}
    for strategy in strategies:
        root = out / _FOLDERS[strategy]
        if root.exists():
            shutil.rmtree(root)
        for s in scripts:
            path = root / s.family / f"{s.name}.yaml"
            path.parent.mkdir(parents=True, exist_ok=True)
            text = s.text
            if strategy == "quasi-static":
                text = text.replace(
                    f"name: {s.name}\n", f"name: {s.name}\nstrategy: quasi-static\n"
                )
            path.write_text(text, "utf-8")
            where[path] = (s.family, strategy)
    return where


class _Progress:
    """One line per finished run on stderr, so a long benchmark shows it is alive."""

    def __init__(self, total: int, console: Console) -> None:
        self.total = total
        self.done = 0
        self.console = console

    def started(self, job: Job) -> None:
        pass

    def progress(self, job: Job, t: float, total: float) -> None:
        pass

    def finished(self, outcome: Outcome) -> None:
        self.done += 1
        note = f" {outcome.wall_time:.0f} s" if outcome.wall_time else ""
        # (A refusal before simulating is counted as refused in the report: say so here too.)
        status = "refused" if refused_by_planner(outcome) else outcome.status
        line = f"[{self.done}/{self.total}] {status:7s} {outcome.job_id}{note}"
        self.console.print(line, markup=False, highlight=False)


def _counts(counter: Counter[str]) -> str:
    return ", ".join(f"{k} {v}" for k, v in counter.most_common()) or "-"


def report(groups: list[Group], verdicts: list[Verdict], wall: float, console: Console) -> None:
    """Print the table, the totals and the refused and failed scripts."""
    table = Table(title="envelope benchmark")
    for col in ("family", "strategy", "total", "succeeded", "refused", "failed", "median RTF"):
        justify = "left" if col in ("family", "strategy", "refused", "failed") else "right"
        table.add_column(col, justify=justify, no_wrap=col in ("family", "strategy"))  # type: ignore[arg-type]
    total = Group("all", "all")
    for v in verdicts:
        total.add(v)
    for g in groups:
        rate = f"{g.succeeded} ({100 * g.succeeded / g.total:.0f} %)" if g.total else "0"
        rtf = _median(g.rtf)
        table.add_row(
            g.family,
            g.strategy,
            str(g.total),
            rate,
            f"{sum(g.refused.values())}: {_counts(g.refused)}" if g.refused else "0",
            f"{sum(g.failed.values())}: {_counts(g.failed)}" if g.failed else "0",
            "-" if rtf is None else f"{rtf:.2f}x",
        )
    rtf = _median(total.rtf)
    table.add_row(
        "all",
        "all",
        str(total.total),
        f"{total.succeeded} ({100 * total.succeeded / max(total.total, 1):.0f} %)",
        f"{sum(total.refused.values())}: {_counts(total.refused)}" if total.refused else "0",
        f"{sum(total.failed.values())}: {_counts(total.failed)}" if total.failed else "0",
        "-" if rtf is None else f"{rtf:.2f}x",
        style="bold",
    )
    console.print(table)
    console.print(
        f"wall time {wall:.1f} s; median real-time factor "
        f"{'-' if rtf is None else f'{rtf:.2f}x'} over {len(total.rtf)} runs",
        highlight=False,
    )
    for status in ("refused", "failed"):
        listed = [v for v in verdicts if v.status == status]
        if not listed:
            continue
        console.print(f"\n{status}:", highlight=False)
        for v in listed:
            console.print(
                f"  {v.path}: {v.reason}: {v.message}\n    rerun: {v.rerun}",
                markup=False,
                highlight=False,
                soft_wrap=True,
            )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--n", type=int, default=30, help="scripts to draw (default 30)")
    parser.add_argument("--seed", type=int, default=0, help="suite seed (default 0)")
    parser.add_argument(
        "--family", action="append", choices=FAMILIES, help="only this family (repeatable)"
    )
    parser.add_argument(
        "--robot",
        default=None,
        help="draw the envelope at this robot's scale (a name under robots/ or a robot.yaml "
        "path; default: HECTOR's ranges as written)",
    )
    parser.add_argument("--strategy", choices=(*STRATEGIES, "both"), default="both")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument("--out", type=Path, default=Path("runs/envelope"))
    parser.add_argument("--json", type=Path, default=None, help="also write the report here")
    parser.add_argument("--timeout", type=float, default=900.0, help="s per run (default 900)")
    args = parser.parse_args(argv)
    if args.n < 1:
        parser.error("--n must be at least 1")
    strategies = STRATEGIES if args.strategy == "both" else (args.strategy,)
    console = Console(highlight=False, width=max(132, Console().width))
    err = Console(stderr=True, highlight=False, width=max(132, Console().width))

    t0 = time.perf_counter()
    scripts = generate_suite(args.n, args.seed, args.family, args.robot)
    where = write_scripts(scripts, args.out, strategies)
    cases = prepare_batch(sorted(where), args.out / "runs", use_cache=False)
    valid = sum(c.job is not None for c in cases)
    err.print(
        f"{len(scripts)} scripts x {len(strategies)} strategies: {len(cases) - valid} refused "
        f"by validation, {valid} to run on {args.jobs} workers",
        highlight=False,
    )
    results = run_batch(cases, workers=args.jobs, timeout=args.timeout,
                        listener=_Progress(valid, err))  # fmt: skip
    wall = time.perf_counter() - t0

    verdicts = []
    for r in results:
        family, strategy = where[r.case.path]
        verdicts.append(verdict(r, family, strategy))
    groups = [
        Group(f, s) for f in FAMILIES for s in strategies if any(x.family == f for x in scripts)
    ]
    by_key = {(g.family, g.strategy): g for g in groups}
    for v in verdicts:
        by_key[(v.family, v.strategy)].add(v)
    report(groups, verdicts, wall, console)

    if args.json is not None:
        rtfs = [v.real_time_factor for v in verdicts if v.real_time_factor is not None]
        doc = {
            "n": args.n,
            "seed": args.seed,
            "robot": args.robot or "hector",
            "families": sorted({s.family for s in scripts}, key=FAMILIES.index),
            "strategies": list(strategies),
            "wall_time_s": round(wall, 2),
            "median_real_time_factor": _median(rtfs),
            "groups": [g.as_json() for g in groups],
            "totals": {
                "total": len(verdicts),
                "succeeded": sum(v.status == "succeeded" for v in verdicts),
                "refused": dict(Counter(v.reason for v in verdicts if v.status == "refused")),
                "failed": dict(Counter(v.reason for v in verdicts if v.status == "failed")),
            },
            "cases": [asdict(v) | {"rerun": v.rerun} for v in verdicts],
        }
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(doc, indent=2) + "\n", "utf-8")
    return 0 if all(v.status == "succeeded" for v in verdicts) else 1


if __name__ == "__main__":
    sys.exit(main())
