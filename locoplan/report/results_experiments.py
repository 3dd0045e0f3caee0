"""The paper's five experiments as locoplan runs, and how each one is checked against it.

Each `Experiment` names a scenario in `scenarios/`, how to run it (a strategy comparison, a
model comparison or a single run), what the paper shows for it (in words: the paper's
images are not available) and which of our plots answers which of its figures. `run_experiment`
runs it and turns the metrics into `Check`s (paper's claim, our number, whether it holds).
Nothing here prints; `locoplan.report.results_doc` writes the Markdown.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from locoplan.compare import (
    Comparison,
    RunTrace,
    Variant,
    VariantOutcome,
    compare_scenario,
    fixture_outlines,
    run_variants,
)
from locoplan.report.compare_plots import PlotFile, comparison_titles, plot_traces, trunk_shift
from locoplan.report.compare_table import object_whereabouts
from locoplan.scenario import Scenario, load_scenario_file
from locoplan.sim.robot_plan import compile_robot_plan

RunKind = Literal["strategies", "models", "single"]


@dataclass(frozen=True, slots=True)
class Check:
    """One line of an experiment's paper-vs-ours table. `ok` None: informational only."""

    what: str
    paper: str
    ours: str
    ok: bool | None


@dataclass(frozen=True, slots=True)
class Experiment:
    """One of the paper's experiments: `key` (also the figure folder), `title`, the scenario
    file name, how to run it, the paper's claims in words, and per plot kind the paper's
    figure it answers (kinds not listed are not drawn)."""

    key: str
    title: str
    scenario_file: str
    run: RunKind
    paper_claims: tuple[str, ...]
    figures: tuple[tuple[str, str], ...]
    command: str


@dataclass(frozen=True, slots=True, eq=False)
class ExperimentResult:
    """What one experiment gave: the runs (and the comparison for two-run experiments), the
    checks, the plots written, and `error` when the experiment could not run at all."""

    experiment: Experiment
    outcomes: tuple[VariantOutcome, ...]
    comparison: Comparison | None
    checks: tuple[Check, ...]
    plots: tuple[PlotFile, ...]
    error: str | None = None


_TOP_VIEW = (
    "Fig. “Package Transfer Simulation Snapshots” (top view): quasi-static (stand still to "
    "pick and drop) against the proposed multi-contact MPC; dotted lines show the direction "
    "the robot faces at the start of each task, shaded sectors the yaw difference between "
    "the pick and drop starts."
)

EXPERIMENTS: tuple[Experiment, ...] = (
    Experiment(
        key="package-transfer",
        title="Package transfer: turn 90°, pick 3 kg, turn -90°, drop on a conveyor",
        scenario_file="package-transfer.yaml",
        run="strategies",
        paper_claims=(
            "With every contact mode known inside the MPC horizon the robot picks while still "
            "turning: the task finishes 1.7 s sooner than the quasi-static approach.",
            "The yaw difference between the pick and drop starts is up to 30° smaller than "
            "with the quasi-static approach.",
            "All left-leg joint torques stay within their limits in this dynamic motion.",
        ),
        figures=(
            ("paths", _TOP_VIEW),
            (
                "yaw",
                "No figure: the 30° and 1.7 s figures are stated in the text (the shaded "
                "sectors of the top-view snapshots).",
            ),
            (
                "torque",
                "Fig. “Torque Plots of Left Leg Joints” (b): the proposed approach in "
                "the package transfer; every torque within its limit.",
            ),
            (
                "contacts",
                "No figure: the text says the quasi-static approach stands still to "
                "pick and drop and turns in place, the proposed one overlaps them.",
            ),
        ),
        command="locoplan compare scenarios/package-transfer.yaml",
    ),
    Experiment(
        key="standing-load",
        title="Standing load: hold 14 kg (82% of the robot's mass) standing",
        scenario_file="standing-load.yaml",
        run="single",
        paper_claims=(
            "With the external-force model the humanoid carries up to 14 kg (82% of its 17 kg) "
            "while standing still.",
            "The left-leg joint torques of this simulation stay within their limits.",
        ),
        figures=(
            (
                "torque",
                "Fig. “Torque Plots of Left Leg Joints” (a): “Simulation of "
                "Load-carrying up to 14 kg”, torques within limits.",
            ),
            (
                "pitch",
                "No figure for the lean at 14 kg (the 5 kg comparison says Model 2 leans back).",
            ),
            ("contacts", "No figure."),
        ),
        command="locoplan run scenarios/standing-load.yaml",
    ),
    Experiment(
        key="model-comparison",
        title="Model comparison: balance holding 5 kg, Model 2 (external force) vs Model 1",
        scenario_file="model-comparison.yaml",
        run="models",
        paper_claims=(
            "With the combined rigid-body model (Model 1) in the controllers the robot cannot "
            "recover from leaning forward when the weight is applied.",
            "With the external-force model (Model 2) the robot handles the weight and adapts "
            "to a favourable pose to carry it: it leans back.",
        ),
        figures=(
            (
                "pitch",
                "Fig. “Comparison of Dynamics Models”: snapshots of 1) the combined "
                "(hybrid) rigid body model leaning forward without recovering and 2) the "
                "external force model leaning back, holding 5 kg.",
            ),
            ("paths", "Same snapshots (the block stays in the hands with Model 2)."),
            ("torque", "No figure."),
            ("contacts", "No figure."),
        ),
        command="locoplan compare scenarios/model-comparison.yaml --models",
    ),
    Experiment(
        key="pick-walk-drop",
        title="Pick, walk and drop a 4 kg box",
        scenario_file="pick-walk-drop.yaml",
        run="single",
        paper_claims=(
            "The robot picks up a 4 kg box, walks and drops it off at the target (orange "
            "region), with the contact schedule given offline from the target location.",
            "MPC at 0.03 s with a horizon of 20 steps bridges the contact-mode changes.",
        ),
        figures=(
            (
                "paths",
                "Fig. “Simulation Snapshots” 1): pick up, walk and drop off a 4 kg box; "
                "blue region = where the box starts, orange = drop-off target.",
            ),
            ("contacts", "No figure (the schedule is given offline)."),
            ("torque", "No figure."),
        ),
        command="locoplan run scenarios/pick-walk-drop.yaml",
    ),
    Experiment(
        key="throw",
        title="Pick a 2 kg ball and throw it while stepping in place",
        scenario_file="throw.yaml",
        run="single",
        paper_claims=(
            "The robot picks up a 2 kg ball, walks in place and throws it while walking "
            "(title figure and snapshots 2), without falling.",
        ),
        figures=(
            (
                "paths",
                "Fig. 1 (title) and Fig. “Simulation Snapshots” 2): pick up, walk in "
                "place and throw a 2 kg ball.",
            ),
            ("contacts", "No figure."),
            ("torque", "No figure."),
        ),
        command="locoplan run scenarios/throw.yaml",
    ),
)


# --- numbers from a run ---------------------------------------------------------------------


def _m(o: VariantOutcome | None, key: str) -> Any:
    return None if o is None or o.metrics is None else o.metrics.get(key)


def _fmt(v: Any, fmt: str = ".2f", unit: str = "") -> str:
    if v is None:
        return "n/a"
    if isinstance(v, bool):
        return "yes" if v else "no"
    return f"{v:{fmt}}{unit}"


def held_pitch_deg(trace: RunTrace | None) -> float | None:
    """Mean trunk pitch (deg, + forward) over the samples where the plan holds an object, or
    None (no trace, nothing held, or the run ended before the hold)."""
    if trace is None or not trace.t.size:
        return None
    held = np.interp(trace.t, trace.t_plan, trace.object_held.astype(float)) > 0.5
    if not held.any():
        return None
    return float(np.degrees(np.mean(trace.base_rpy[held, 1])))


def held_shift_cm(trace: RunTrace | None) -> float | None:
    """Mean trunk shift along the initial heading (cm, negative = back) over the samples where
    the plan holds an object, or None."""
    if trace is None or not trace.t.size:
        return None
    held = np.interp(trace.t, trace.t_plan, trace.object_held.astype(float)) > 0.5
    if not held.any():
        return None
    return float(100.0 * np.mean(trunk_shift(trace)[held]))


def _on(o: VariantOutcome | None, obj: str) -> str | None:
    objects = _m(o, "objects") or {}
    return (objects.get(obj) or {}).get("on")


def _where(o: VariantOutcome | None, obj: str) -> str:
    entry = (_m(o, "objects") or {}).get(obj)
    return "n/a" if entry is None else object_whereabouts(entry)


def _held_at_end(o: VariantOutcome | None, obj: str) -> bool | None:
    objects = _m(o, "objects") or {}
    entry = objects.get(obj)
    return None if entry is None else bool(entry.get("held"))


def _ran(o: VariantOutcome | None) -> str:
    if o is None:
        return "not run"
    if o.error is not None:
        return f"run broke: {o.error}"
    return ""


def _no_fall(o: VariantOutcome | None) -> Check:
    label = "—" if o is None else o.label
    fell = _m(o, "fell")
    ours = _ran(o) or (
        f"fell at {_m(o, 'fall_time'):.2f} s" if fell and _m(o, "fall_time") else _fmt(not fell)
    )
    return Check(
        f"stays up ({label})",
        "yes",
        ours if fell is not None else _ran(o) or "n/a",
        None if fell is None else not fell,
    )


def _torque(o: VariantOutcome | None, paper: str = "within limits") -> Check:
    ratio = _m(o, "peak_torque_ratio")
    joint = _m(o, "peak_torque_joint")
    label = "—" if o is None else o.label
    ours = _ran(o) or f"peak |τ|/limit {_fmt(ratio)} ({joint})"
    if ratio is not None and ratio >= 0.999:
        # MuJoCo clips at the actuator limit, so 1.00 means saturated, not exceeded.
        ours += f", saturated at the limit ({_m(o, 'torque_clips')} torque clips)"
    return Check(
        f"torques within limits ({label})", paper, ours, None if ratio is None else ratio <= 1.0
    )


# --- checks per experiment ------------------------------------------------------------------


def _checks_package_transfer(c: Comparison, scenario: Scenario) -> list[Check]:
    qs, dyn = c.outcome("quasi-static"), c.outcome("dynamic")
    out: list[Check] = []
    t_qs, t_dyn = _m(qs, "completion_time"), _m(dyn, "completion_time")
    if t_qs is not None and t_dyn is not None:
        faster = t_qs - t_dyn
        out.append(
            Check(
                "dynamic finishes sooner by",
                "1.7 s",
                f"{faster:.2f} s ({t_dyn:.2f} s vs {t_qs:.2f} s)",
                faster >= 1.0,
            )
        )
    else:
        planned = compile_robot_plan(scenario, "quasi-static").end_shift
        out.append(
            Check(
                "dynamic finishes sooner by",
                "1.7 s",
                f"n/a: not completed (quasi-static {_fmt(t_qs)}, dynamic "
                f"{_fmt(t_dyn)}); the plans differ by {planned:.2f} s",
                False,
            )
        )
    # From the traces: the metric interpolates past a fall, the trace says "not reached".
    y_qs = None if qs.trace is None else qs.trace.yaw_difference_deg
    y_dyn = None if dyn.trace is None else dyn.trace.yaw_difference_deg
    if y_qs is not None and y_dyn is not None:
        less = y_qs - y_dyn
        out.append(
            Check(
                "pick→drop yaw difference smaller by",
                "up to 30°",
                f"{less:.1f}° ({y_dyn:.1f}° vs {y_qs:.1f}°)",
                less >= 15.0,
            )
        )
    else:
        missing = [o.label for o, y in ((qs, y_qs), (dyn, y_dyn)) if y is None]
        out.append(
            Check(
                "pick→drop yaw difference smaller by",
                "up to 30°",
                f"n/a: {', '.join(missing)} did not reach the drop start",
                False,
            )
        )
    for o in (qs, dyn):
        on = _on(o, "package") if not _held_at_end(o, "package") else None
        out.append(
            Check(
                f"package on the conveyor ({o.label})",
                "yes",
                _ran(o) or _where(o, "package"),
                on == "conveyor",
            )
        )
    out += [_no_fall(qs), _no_fall(dyn), _torque(qs, "not shown"), _torque(dyn)]
    return out


def _checks_standing_load(o: VariantOutcome, trace: RunTrace | None) -> list[Check]:
    held = _held_at_end(o, "block")
    lean = held_pitch_deg(trace)
    return [
        Check("holds the 14 kg block to the end", "yes", _ran(o) or _fmt(held), bool(held)),
        _no_fall(o),
        _torque(o),
        Check(
            "trunk lean while holding (mean pitch, + forward)",
            "not stated for 14 kg",
            _fmt(lean, "+.1f", "°"),
            None,
        ),
        Check(
            "trunk shift while holding (mean, along the start heading)",
            "not stated for 14 kg",
            _fmt(held_shift_cm(trace), "+.1f", " cm"),
            None,
        ),
    ]


def _checks_model_comparison(c: Comparison) -> list[Check]:
    ext, comb = c.outcome("external-force"), c.outcome("combined")
    lean_ext = held_pitch_deg(ext.trace)
    lean_comb = held_pitch_deg(comb.trace)
    fell_comb = _m(comb, "fell")
    return [
        _no_fall(ext),
        Check(
            "Model 2 leans back while holding (mean pitch)",
            "leans back",
            _fmt(lean_ext, "+.1f", "°"),
            None if lean_ext is None else lean_ext < 0.0,
        ),
        Check(
            "trunk shift while holding (mean, along the start heading)",
            "Model 2 moves back, Model 1 forward (snapshots)",
            f"external-force {_fmt(held_shift_cm(ext.trace), '+.1f', ' cm')}, "
            f"combined {_fmt(held_shift_cm(comb.trace), '+.1f', ' cm')}",
            None,
        ),
        Check(
            "Model 2 holds the block to the end",
            "yes",
            _ran(ext) or _fmt(_held_at_end(ext, "block")),
            bool(_held_at_end(ext, "block")),
        ),
        Check(
            "Model 1 (combined) falls forward",
            "cannot recover from leaning forward",
            _ran(comb)
            or ("fell" if fell_comb else "stays up")
            + f", mean pitch {_fmt(lean_comb, '+.1f', '°')}",
            None if fell_comb is None else bool(fell_comb),
        ),
        _torque(ext, "not shown"),
    ]


def _carried_distance(trace: RunTrace | None, obj: str) -> float | None:
    if trace is None or obj not in trace.object_positions or not trace.t.size:
        return None
    p = trace.object_positions[obj]
    return float(np.linalg.norm(p[-1, :2] - p[0, :2]))


def _checks_pick_walk_drop(o: VariantOutcome, trace: RunTrace | None) -> list[Check]:
    on = _on(o, "box") if not _held_at_end(o, "box") else None
    dist = _carried_distance(trace, "box")
    return [
        Check(
            "box placed on the platform",
            "yes (orange target)",
            _ran(o) or _where(o, "box"),
            on == "platform",
        ),
        Check(
            "box carried (start to end, horizontal)",
            "a walk (distance not stated)",
            _fmt(dist, ".2f", " m"),
            None if dist is None else dist >= 0.5,
        ),
        _no_fall(o),
        _torque(o, "not shown"),
    ]


def _landing_error(
    trace: RunTrace | None, scenario: Scenario, obj: str
) -> tuple[float | None, str]:
    """Horizontal distance (m) from the first floor contact of the thrown object to the
    plan's ballistic landing point, and a note."""
    target = compile_robot_plan(scenario).object_target(obj)
    if trace is None or target.position is None or obj not in trace.object_positions:
        return None, "no trace or no planned landing point"
    p = trace.object_positions[obj]
    radius = scenario.objects[obj].size[0]
    # 1 cm above resting on the floor counts as touching it.
    low = np.flatnonzero(p[:, 2] <= radius + 0.01)
    if not low.size:
        return None, "the ball never reached the floor"
    landed = p[low[0], :2]
    err = float(np.linalg.norm(landed - np.asarray(target.position[:2])))
    return err, f"landed at ({landed[0]:.2f}, {landed[1]:.2f}) m"


def _checks_throw(o: VariantOutcome, trace: RunTrace | None, scenario: Scenario) -> list[Check]:
    err, note = _landing_error(trace, scenario, "ball")
    return [
        Check(
            "ball thrown while stepping, lands near the ballistic prediction",
            "thrown (landing not reported)",
            _ran(o)
            or (f"{err * 100:.0f} cm from the prediction, {note}" if err is not None else note),
            None if err is None else err <= 0.15,
        ),
        _no_fall(o),
        _torque(o, "not shown"),
    ]


def _checks_generic(outcomes: Sequence[VariantOutcome]) -> list[Check]:
    return [c for o in outcomes for c in (_no_fall(o), _torque(o, "not shown"))]


def experiment_checks(
    key: str,
    outcomes: Sequence[VariantOutcome],
    comparison: Comparison | None,
    scenario: Scenario,
) -> list[Check]:
    """The paper-vs-ours checks of the experiment `key` (one of EXPERIMENTS' keys); another
    key gets the generic ones (stays up, torques within limits) for every run."""
    one = outcomes[0] if len(outcomes) == 1 else None
    if key == "package-transfer" and comparison is not None:
        return _checks_package_transfer(comparison, scenario)
    if key == "model-comparison" and comparison is not None:
        return _checks_model_comparison(comparison)
    if key == "standing-load" and one is not None:
        return _checks_standing_load(one, one.trace)
    if key == "pick-walk-drop" and one is not None:
        return _checks_pick_walk_drop(one, one.trace)
    if key == "throw" and one is not None:
        return _checks_throw(one, one.trace, scenario)
    return _checks_generic(outcomes)


# --- running --------------------------------------------------------------------------------


def run_experiment(
    exp: Experiment,
    scenarios_dir: Path,
    figures_dir: Path,
    runs_dir: Path,
    *,
    jobs: int | None = None,
    dpi: int = 90,
    progress: Callable[[str, float, float], None] | None = None,
) -> ExperimentResult:
    """Run one experiment, check it and draw its plots into `figures_dir/<key>/`. Never
    raises for a failing or broken run (that is a result); a script that cannot be loaded
    or planned, or a bug, is reported in `error`."""
    try:
        return _run(exp, scenarios_dir, figures_dir, runs_dir, jobs, dpi, progress)
    except Exception as exc:  # the doc must still be written: report, do not stop
        return ExperimentResult(exp, (), None, (), (), f"{type(exc).__name__}: {exc}")


def _run(
    exp: Experiment,
    scenarios_dir: Path,
    figures_dir: Path,
    runs_dir: Path,
    jobs: int | None,
    dpi: int,
    progress: Callable[[str, float, float], None] | None,
) -> ExperimentResult:
    loaded = load_scenario_file(str(scenarios_dir / exp.scenario_file), None)
    scenario, text = loaded.scenario, loaded.text
    out_runs = runs_dir / exp.key
    kinds = [k for k, _ in exp.figures]
    comparison: Comparison | None = None
    if exp.run in ("strategies", "models"):
        comparison = compare_scenario(
            scenario, text, out_runs, kind=exp.run, jobs=jobs, progress=progress
        )
        outcomes: tuple[VariantOutcome, ...] = comparison.outcomes
    else:
        variant = Variant(scenario.strategy, scenario.strategy, scenario.model, scenario.name)
        outcomes = run_variants(scenario, text, [variant], out_runs, jobs=1, progress=progress)
    checks = experiment_checks(exp.key, outcomes, comparison, scenario)
    traces: Sequence[RunTrace] = [o.trace for o in outcomes if o.trace is not None]
    titles = comparison_titles(scenario.name, [o.label for o in outcomes])
    plots = plot_traces(
        traces,
        figures_dir / exp.key,
        fixtures=fixture_outlines(scenario),
        kinds=kinds,
        titles=titles,
        dpi=dpi,
    )
    return ExperimentResult(exp, outcomes, comparison, tuple(checks), plots)


def verdict(result: ExperimentResult) -> str:
    """ "reproduced", "partly" or "not reproduced" from the checks that can fail, or "error"."""
    if result.error is not None:
        return "error"
    oks = [c.ok for c in result.checks if c.ok is not None]
    if oks and all(oks):
        return "reproduced"
    if any(oks):
        return "partly"
    return "not reproduced"
