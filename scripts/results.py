"""Regenerate docs/results.md and its plots (what `make results` runs).

Runs the paper's five experiments (scenarios/*.yaml) closed loop, draws the plots into
docs/results/<experiment>/ and writes docs/results.md; MCAP logs go to runs/results/.
Failing experiments are reported in the document, so the exit status is 0 whenever the
document was written (2 for bad arguments).

    .venv/bin/python scripts/results.py [--scenarios DIR] [--doc PATH] [--figures DIR]
                                        [--runs DIR] [--jobs N] [--only KEY ...]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from locoplan.report.results_doc import write_results
from locoplan.report.results_experiments import EXPERIMENTS, ExperimentResult, verdict


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", type=Path, default=Path("scenarios"))
    parser.add_argument("--doc", type=Path, default=Path("docs/results.md"))
    parser.add_argument("--figures", type=Path, default=Path("docs/results"))
    parser.add_argument("--runs", type=Path, default=Path("runs/results"))
    parser.add_argument("--jobs", type=int, default=None, help="processes per comparison")
    parser.add_argument(
        "--only",
        nargs="+",
        choices=[e.key for e in EXPERIMENTS],
        help="run only these experiments (the document then lists only them)",
    )
    args = parser.parse_args(argv)
    if args.jobs is not None and args.jobs < 1:
        parser.error("--jobs must be at least 1")
    experiments = [e for e in EXPERIMENTS if not args.only or e.key in args.only]
    t0 = time.perf_counter()

    def done(r: ExperimentResult) -> None:
        runs = ", ".join(
            f"{o.label}: {'broke' if o.broke else ('passed' if o.passed else 'failed')}"
            for o in r.outcomes
        )
        extra = f" ({r.error})" if r.error else ""
        print(
            f"[{time.perf_counter() - t0:6.1f} s] {r.experiment.key}: {verdict(r)}{extra}"
            f"{'; ' + runs if runs else ''}",
            flush=True,
        )

    write_results(
        args.scenarios,
        args.doc,
        args.figures,
        args.runs,
        experiments=experiments,
        jobs=args.jobs,
        done=done,
    )
    print(f"wrote {args.doc} and plots under {args.figures}/", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
