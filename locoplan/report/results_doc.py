"""docs/results.md: the paper's experiments next to ours (`make results`).

`build_results` runs every experiment of `locoplan.report.results_experiments`, draws the
plots under `figures_dir/<experiment>/` and returns the Markdown; `write_results` also writes
it. A failing or broken run, or an experiment that cannot run at all, is reported in the
document (never raised), so the document is always complete and honest. Nothing here prints.
"""

from __future__ import annotations

import datetime
import os
import platform
import subprocess
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from locoplan import __version__
from locoplan.compare import VariantOutcome
from locoplan.report.compare_table import object_whereabouts
from locoplan.report.results_experiments import (
    EXPERIMENTS,
    Experiment,
    ExperimentResult,
    run_experiment,
    verdict,
)

# (experiment key, label, simulated time s, total s) progress; (key, result) when one is done.
ResultsProgress = Callable[[str, str, float, float], None]
ExperimentDone = Callable[[ExperimentResult], None]

_VERDICT_MARK = {
    "reproduced": "✅ reproduced",
    "partly": "⚠️ partly",
    "not reproduced": "❌ not reproduced",
    "error": "❌ could not run",
}


def _cell(text: str) -> str:
    """Text safe inside a Markdown table cell."""
    return text.replace("|", "\\|").replace("\n", " ")


def _ok(ok: bool | None) -> str:
    return "—" if ok is None else ("✅" if ok else "❌")


def _num(v: Any, fmt: str, unit: str = "") -> str:
    if v is None:
        return "n/a"
    if isinstance(v, bool):
        return "yes" if v else "no"
    return f"{v:{fmt}}{unit}"


def _git_revision(repo: Path) -> str | None:
    try:
        res = subprocess.run(
            ["git", "-C", str(repo), "describe", "--always", "--dirty"],
            capture_output=True,
            text=True,
            timeout=10,
            check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return res.stdout.strip() or None


def _metrics_table(outcomes: Sequence[VariantOutcome]) -> list[str]:
    rows = [
        "| run | completed | completion time | yaw diff. pick→drop | peak torque ratio (joint) "
        "| fell | objects at the end | MPC update p99 | real-time factor | expectations |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for o in outcomes:
        if o.metrics is None:
            rows.append(f"| {o.label} | run broke: {_cell(o.error or '?')} |||||||||")
            continue
        m = o.metrics
        objects = ", ".join(
            f"{name} {object_whereabouts(v)}" for name, v in (m.get("objects") or {}).items()
        )
        failed = [k for k, e in (m.get("expectations") or {}).items() if not e["ok"]]
        fell = _num(m.get("fell"), "")
        if m.get("fell") and m.get("fall_time") is not None:
            fell = f"yes, at {m['fall_time']:.2f} s"
        rows.append(
            "| "
            + " | ".join(
                [
                    o.label,
                    _num(m.get("completed"), ""),
                    _num(m.get("completion_time"), ".2f", " s"),
                    _num(m.get("yaw_difference_deg"), ".1f", "°"),
                    f"{_num(m.get('peak_torque_ratio'), '.2f')} ({m.get('peak_torque_joint')})",
                    fell,
                    _cell(objects or "—"),
                    _num((m.get("mpc_solve_ms") or {}).get("p99"), ".1f", " ms"),
                    _num(m.get("real_time_factor"), ".2f", "×"),
                    "all held" if not failed else "failed: " + ", ".join(failed),
                ]
            )
            + " |"
        )
    return rows


def _experiment_section(
    n: int, r: ExperimentResult, doc_dir: Path, scenarios_rel: str
) -> list[str]:
    exp = r.experiment
    lines = [
        f"## {n}. {exp.title}",
        "",
        f"Script: [`{scenarios_rel}/{exp.scenario_file}`]({scenarios_rel}/{exp.scenario_file})"
        f" · reproduce with `{exp.command}` · verdict: **{_VERDICT_MARK[verdict(r)]}**",
        "",
        "**The paper** (its images are not available; its claims in words):",
        "",
        *[f"- {claim}" for claim in exp.paper_claims],
        "",
    ]
    if r.error is not None:
        lines += [
            f"**Ours: the experiment could not run:** `{_cell(r.error)}`",
            "",
        ]
        return lines
    lines += [
        "**Paper vs ours:**",
        "",
        "| what | paper | ours | holds |",
        "|---|---|---|---|",
        *[
            f"| {_cell(c.what)} | {_cell(c.paper)} | {_cell(c.ours)} | {_ok(c.ok)} |"
            for c in r.checks
        ],
        "",
        "**Our runs** (metrics as in `compare.json` / `--metrics-json`):",
        "",
        *_metrics_table(r.outcomes),
        "",
    ]
    broke = [o for o in r.outcomes if o.error is not None]
    for o in broke:
        lines += [f"> The {o.label} run broke: {_cell(o.error or '')}", ""]
    if r.comparison is not None and r.comparison.schedule_note:
        lines += [f"> {r.comparison.schedule_note}", ""]
    plots = {p.kind: p for p in r.plots}
    lines += ["| the paper's figure | ours |", "|---|---|"]
    for kind, paper in exp.figures:
        plot = plots.get(kind)
        if plot is None:
            ours = "no plot (no run produced data)"
        else:
            rel = os.path.relpath(plot.path, doc_dir)
            ours = f"![{exp.key} {kind}]({rel})"
        lines.append(f"| {_cell(paper)} | {ours} |")
    lines.append("")
    return lines


def render_results(
    results: Sequence[ExperimentResult],
    doc_dir: Path,
    scenarios_dir: Path,
    *,
    revision: str | None = None,
    generated: datetime.datetime | None = None,
) -> str:
    """The Markdown of docs/results.md for `results` (links relative to `doc_dir`)."""
    scenarios_rel = os.path.relpath(scenarios_dir, doc_dir)
    when = (generated or datetime.datetime.now(datetime.UTC)).strftime("%Y-%m-%d %H:%M UTC")
    rev = f", revision `{revision}`" if revision else ""
    lines = [
        "# Results: the paper's experiments, reproduced",
        "",
        "Li & Nguyen, *Multi-contact MPC for Dynamic Loco-manipulation on Humanoid Robots*, "
        "against locoplan's closed loop in MuJoCo (multi-contact MPC + WBC on a 17 kg "
        "HECTOR-class humanoid). Generated by `make results` from the scripts in "
        f"`{scenarios_rel}/` on {when} (locoplan {__version__}{rev}, Python "
        f"{platform.python_version()}). Every number below comes from the simulation state "
        "(MuJoCo), not from the controller's intentions; the paper's images are not "
        "available, so its figures are described in words next to our plots.",
        "",
        "How to read the checks: ✅ holds, ❌ does not hold, — informational. The thresholds "
        "are the project's acceptance criteria (package transfer: dynamic at least 1.0 s "
        "sooner and at least 15° less yaw difference; throw: landing within 15 cm of the "
        "ballistic prediction; pick-walk-drop: box carried 0.5 m or more).",
        "",
        "| # | experiment | verdict | failed checks |",
        "|---|---|---|---|",
    ]
    for n, r in enumerate(results, 1):
        failed = [c.what for c in r.checks if c.ok is False]
        note = _cell(r.error) if r.error else (", ".join(failed) if failed else "—")
        anchor = f"#{n}-" + "-".join(
            "".join(ch for ch in r.experiment.title.lower() if ch.isalnum() or ch in " -").split()
        )
        lines.append(
            f"| {n} | [{_cell(r.experiment.title)}]({anchor}) | {_VERDICT_MARK[verdict(r)]} "
            f"| {_cell(note)} |"
        )
    lines.append("")
    for n, r in enumerate(results, 1):
        lines += _experiment_section(n, r, doc_dir, scenarios_rel)
    lines += [
        "## Plots",
        "",
        "- **yaw**: trunk yaw over time (solid: measured, dashed: planned) with the pick start "
        "(dotted) and drop start (dash-dot) of each run; the bracket is the paper's yaw "
        "difference.",
        "- **contacts**: planned foot stance, hand contact and object-held intervals of every "
        "run on one time axis, with whether the simulated object is off its support; hatched: "
        "after a fall.",
        "- **torque**: each left-leg joint's applied torque against its limit band (grey, "
        "dashed limits), as in the paper's torque figure.",
        "- **paths**: top view of the trunk and object paths over the fixtures, with the "
        "heading at the pick and drop starts; objects' height over time.",
        "- **pitch**: trunk pitch (+ leaning forward) and height; bars at the top mark when an "
        "object is held.",
        "",
    ]
    return "\n".join(lines)


def build_results(
    scenarios_dir: Path,
    doc_path: Path,
    figures_dir: Path,
    runs_dir: Path,
    *,
    experiments: Sequence[Experiment] = EXPERIMENTS,
    jobs: int | None = None,
    progress: ResultsProgress | None = None,
    done: ExperimentDone | None = None,
) -> tuple[str, tuple[ExperimentResult, ...]]:
    """Run `experiments` and return (Markdown, results). Plots go to
    `figures_dir/<key>/`, MCAP logs to `runs_dir/<key>/`; links are relative to
    `doc_path`'s directory. Does not write `doc_path` (see `write_results`)."""
    results = []
    for exp in experiments:

        def on_progress(label: str, t: float, total: float, key: str = exp.key) -> None:
            if progress is not None:
                progress(key, label, t, total)

        r = run_experiment(
            exp, scenarios_dir, figures_dir, runs_dir, jobs=jobs, progress=on_progress
        )
        results.append(r)
        if done is not None:
            done(r)
    text = render_results(
        results,
        doc_path.parent,
        scenarios_dir,
        revision=_git_revision(doc_path.parent),
    )
    return text, tuple(results)


def write_results(
    scenarios_dir: Path,
    doc_path: Path,
    figures_dir: Path,
    runs_dir: Path,
    **kwargs: Any,
) -> tuple[ExperimentResult, ...]:
    """`build_results` and write the Markdown to `doc_path`; returns the results."""
    text, results = build_results(scenarios_dir, doc_path, figures_dir, runs_dir, **kwargs)
    doc_path.parent.mkdir(parents=True, exist_ok=True)
    doc_path.write_text(text, "utf-8")
    return results
