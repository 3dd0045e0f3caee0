"""`compare_scenario`: one script, two variants, side by side (what `locoplan compare` does).

The comparison runs both variants (see `locoplan.compare.variants`), keeps their metrics and
plot series, and says whether the two contact schedules were identical: when the quasi-static
re-timing moves no task (no locomotion overlaps manipulation), both strategies simulate the
same plan and their completion times must agree within one MPC step.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from locoplan.compare.runner import VariantOutcome, VariantProgress, run_variants
from locoplan.compare.trace import FixtureOutline, fixture_outlines
from locoplan.compare.variants import (
    CompareKind,
    baseline_and_proposed,
    comparison_variants,
    compile_variant_plans,
    schedules_identical,
)
from locoplan.scenario import Scenario
from locoplan.sim.live import LiveView

# Metrics shown with a difference column (proposed - baseline); key path into the metrics.
DIFFERENCE_KEYS: dict[str, tuple[str, ...]] = {
    "completion_time": ("completion_time",),
    "yaw_difference_deg": ("yaw_difference_deg",),
    "peak_torque_ratio": ("peak_torque_ratio",),
    "mpc_solve_p99_ms": ("mpc_solve_ms", "p99"),
    "real_time_factor": ("real_time_factor",),
}


@dataclass(frozen=True, slots=True, eq=False)
class Comparison:
    """Two runs of one script.

    `kind`: "strategies" or "models"; `outcomes`: the two runs in compare.json order
    (quasi-static, dynamic) or (external-force, combined); `schedules_identical`: both plans
    schedule every task at the same times; `schedule_note`: what that implies for this run
    (None when the schedules differ); `mpc_dt` (s): the script's MPC step, the tolerance on
    equal completion times; `fixtures`: top-view outlines for the path plot.
    """

    scenario_name: str
    kind: CompareKind
    outcomes: tuple[VariantOutcome, VariantOutcome]
    schedules_identical: bool
    schedule_note: str | None
    mpc_dt: float
    fixtures: tuple[FixtureOutline, ...]
    out_dir: Path

    @property
    def labels(self) -> tuple[str, str]:
        """The two labels in compare.json order."""
        return self.outcomes[0].label, self.outcomes[1].label

    def outcome(self, label: str) -> VariantOutcome:
        """The outcome with this label (KeyError otherwise)."""
        for o in self.outcomes:
            if o.label == label:
                return o
        raise KeyError(label)

    @property
    def baseline(self) -> VariantOutcome:
        """The paper's baseline: quasi-static, or the combined model (Model 1)."""
        return self.outcome(baseline_and_proposed(self.kind)[0])

    @property
    def proposed(self) -> VariantOutcome:
        """The paper's proposal: dynamic, or the external-force model (Model 2)."""
        return self.outcome(baseline_and_proposed(self.kind)[1])

    @property
    def broke(self) -> bool:
        """Whether at least one run broke (exit 3)."""
        return any(o.broke for o in self.outcomes)

    @property
    def passed(self) -> bool:
        """Whether both runs finished and every expectation held in both (exit 0)."""
        return all(o.passed for o in self.outcomes)

    @property
    def completion_times_agree(self) -> bool | None:
        """With identical schedules: whether both completion times exist and agree within one
        MPC step; None when the schedules differ (nothing to check)."""
        if not self.schedules_identical:
            return None
        a, b = (_get(o.metrics, ("completion_time",)) for o in self.outcomes)
        return a is not None and b is not None and abs(a - b) <= self.mpc_dt + 1e-9

    def differences(self) -> dict[str, float | None]:
        """proposed - baseline for each of DIFFERENCE_KEYS (None where either is missing)."""
        out: dict[str, float | None] = {}
        for name, path in DIFFERENCE_KEYS.items():
            a = _get(self.baseline.metrics, path)
            b = _get(self.proposed.metrics, path)
            out[name] = None if a is None or b is None else round(b - a, 4)
        return out

    def to_json(self) -> dict[str, Any]:
        """The compare.json object: {label: metrics} in contract order. A run that broke has
        no metrics; it gets {scenario, strategy, model, error, passed: false, log}."""
        out: dict[str, Any] = {}
        for o in self.outcomes:
            if o.metrics is not None:
                out[o.label] = o.metrics
            else:
                out[o.label] = {
                    "scenario": self.scenario_name,
                    "strategy": o.variant.strategy,
                    "model": o.variant.model,
                    "error": o.error,
                    "passed": False,
                    "log": None if o.log_path is None else str(o.log_path),
                }
        return out


def _get(metrics: Mapping[str, Any] | None, path: tuple[str, ...]) -> float | None:
    value: Any = metrics
    for key in path:
        if not isinstance(value, Mapping):
            return None
        value = value.get(key)
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value)


def _schedule_note(
    kind: CompareKind, identical: bool, outcomes: tuple[VariantOutcome, ...], mpc_dt: float
) -> str | None:
    if kind != "strategies" or not identical:
        return None
    head = (
        "schedules identical: no locomotion overlaps manipulation, so the quasi-static "
        "re-timing moves no task"
    )
    times = [(o.label, _get(o.metrics, ("completion_time",))) for o in outcomes]
    missing = [label for label, v in times if v is None]
    if missing:
        return f"{head}; completion times not comparable ({', '.join(missing)} did not complete)"
    (la, a), (lb, b) = times
    assert a is not None and b is not None
    if abs(a - b) <= mpc_dt + 1e-9:
        return (
            f"{head}; completion times {a:.3f} s ({la}) and {b:.3f} s ({lb}) agree within "
            f"one MPC step ({mpc_dt:g} s)"
        )
    return (
        f"{head}; but completion times {a:.3f} s ({la}) and {b:.3f} s ({lb}) differ by "
        f"{abs(a - b):.3f} s, more than one MPC step ({mpc_dt:g} s)"
    )


def compare_scenario(
    scenario: Scenario,
    text: str,
    out_dir: Path,
    *,
    kind: CompareKind = "strategies",
    strategy: str | None = None,
    jobs: int | None = None,
    qp_backend: str = "daqp",
    progress: VariantProgress | None = None,
    live: LiveView | None = None,
) -> Comparison:
    """Run `scenario` under both variants of `kind` and compare.

    Both plans are compiled first, so a script the compiler rejects raises `PlanError`
    before anything runs. Logs go to `out_dir/<scenario>-<label>.mcap`; nothing else is
    written (see `write_compare_json` and `locoplan.report.compare_plots`). `strategy` is the
    one strategy of a "models" comparison (default: the script's). Raises ValueError for a
    bad `kind`, `strategy` with "strategies", or jobs < 1. With `live`, the runs go one
    after the other in this process, each served live while it runs (`locoplan.sim.live`).
    """
    variants = comparison_variants(scenario, kind, strategy)
    plans = compile_variant_plans(scenario, variants)
    identical = schedules_identical(plans[0], plans[1])
    outcomes = run_variants(
        scenario,
        text,
        variants,
        out_dir,
        jobs=jobs,
        qp_backend=qp_backend,
        progress=progress,
        live=live,
    )
    pair = (outcomes[0], outcomes[1])
    return Comparison(
        scenario_name=scenario.name,
        kind=kind,
        outcomes=pair,
        schedules_identical=identical,
        schedule_note=_schedule_note(kind, identical, pair, scenario.mpc.dt),
        mpc_dt=scenario.mpc.dt,
        fixtures=fixture_outlines(scenario),
        out_dir=out_dir,
    )


def write_compare_json(comparison: Comparison, path: Path) -> Path:
    """Write compare.json (`Comparison.to_json`) to `path`; returns the path."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(comparison.to_json(), indent=2) + "\n", "utf-8")
    return path
