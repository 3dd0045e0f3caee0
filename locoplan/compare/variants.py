"""The two runs of a comparison and whether their contact schedules differ at all.

`locoplan compare` runs one script twice: under both strategies (quasi-static re-timing from
the plan compiler vs the written dynamic timing) or, with `--models`, under both SRBD models
(the paper's Model 2 "external-force" vs Model 1 "combined") on one strategy.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from locoplan.plan import Plan
from locoplan.scenario import Scenario
from locoplan.sim.robot_plan import compile_robot_plan

CompareKind = Literal["strategies", "models"]
MODELS = ("external-force", "combined")
# Key order of compare.json (shared/cli-contract.md) and column order of the table.
STRATEGY_LABELS = ("quasi-static", "dynamic")
MODEL_LABELS = MODELS
SCHEDULE_TOL = 1e-9  # s: task times equal up to float noise of start + shift


@dataclass(frozen=True, slots=True)
class Variant:
    """One run of a comparison: its label (a compare.json key), the strategy and model it
    runs with, and the stem of its MCAP log (`<scenario>-<label>`)."""

    label: str
    strategy: str
    model: str
    log_name: str


def comparison_variants(
    scenario: Scenario, kind: CompareKind, strategy: str | None = None
) -> tuple[Variant, Variant]:
    """The two variants in compare.json order.

    "strategies": quasi-static then dynamic, both with the script's model. "models":
    external-force then combined, both with `strategy` (default: the script's). `strategy` is
    rejected for "strategies" (ValueError): both strategies run there.
    """
    if kind == "strategies":
        if strategy is not None:
            raise ValueError("a strategy comparison runs both strategies; strategy must be None")
        return tuple(  # type: ignore[return-value]
            Variant(s, s, scenario.model, f"{scenario.name}-{s}") for s in STRATEGY_LABELS
        )
    if kind == "models":
        s = scenario.strategy if strategy is None else strategy
        return tuple(  # type: ignore[return-value]
            Variant(m, s, m, f"{scenario.name}-{m}") for m in MODEL_LABELS
        )
    raise ValueError(f"unknown comparison kind {kind!r}; allowed: strategies, models")


def baseline_and_proposed(kind: CompareKind) -> tuple[str, str]:
    """Labels of the paper's baseline and of its proposal: the difference column of the
    table is proposed - baseline (quasi-static -> dynamic; combined -> external-force)."""
    return ("quasi-static", "dynamic") if kind == "strategies" else ("combined", "external-force")


def schedules_identical(a: Plan, b: Plan) -> bool:
    """Whether two plans schedule every task at the same times (so the contact schedules,
    references and end time are the same)."""
    if len(a.tasks) != len(b.tasks) or abs(a.t_end - b.t_end) > SCHEDULE_TOL:
        return False
    return all(
        x.index == y.index
        and abs(x.start - y.start) <= SCHEDULE_TOL
        and abs(x.end - y.end) <= SCHEDULE_TOL
        for x, y in zip(a.tasks, b.tasks, strict=True)
    )


def compile_variant_plans(scenario: Scenario, variants: tuple[Variant, ...]) -> tuple[Plan, ...]:
    """Compile each variant's plan for the script's robot (raises PlanError: bad input,
    before anything runs)."""
    return tuple(compile_robot_plan(scenario, v.strategy) for v in variants)
