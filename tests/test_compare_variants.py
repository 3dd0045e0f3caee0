"""Comparison variants and schedule identity, from compiled plans (no simulation)."""

from __future__ import annotations

import pytest
from compare_fixtures import SHORT_TURN, TURN_THEN_PICK, repo_scenario_text

from locoplan.compare import baseline_and_proposed, comparison_variants, schedules_identical
from locoplan.compare.variants import compile_variant_plans
from locoplan.plan import compile_plan
from locoplan.scenario import load_scenario


def test_strategy_variants_in_contract_order() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    qs, dyn = comparison_variants(scenario, "strategies")
    assert (qs.label, qs.strategy, dyn.label, dyn.strategy) == (
        "quasi-static",
        "quasi-static",
        "dynamic",
        "dynamic",
    )
    assert qs.model == dyn.model == scenario.model
    assert (qs.log_name, dyn.log_name) == (
        "package-transfer-quasi-static",
        "package-transfer-dynamic",
    )


def test_model_variants_share_one_strategy() -> None:
    scenario, _ = repo_scenario_text("model-comparison")
    ext, comb = comparison_variants(scenario, "models")
    assert (ext.label, comb.label) == ("external-force", "combined")
    assert (ext.model, comb.model) == ("external-force", "combined")
    assert ext.strategy == comb.strategy == scenario.strategy
    qs = comparison_variants(scenario, "models", "quasi-static")
    assert {v.strategy for v in qs} == {"quasi-static"}
    assert ext.log_name != comb.log_name


def test_bad_arguments_rejected() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    with pytest.raises(ValueError, match="runs both strategies"):
        comparison_variants(scenario, "strategies", "dynamic")
    with pytest.raises(ValueError, match="unknown comparison kind"):
        comparison_variants(scenario, "robots")  # type: ignore[arg-type]


def test_baseline_and_proposed_follow_the_paper() -> None:
    assert baseline_and_proposed("strategies") == ("quasi-static", "dynamic")
    assert baseline_and_proposed("models") == ("combined", "external-force")


def test_package_transfer_schedules_differ() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    qs, dyn = compile_variant_plans(scenario, comparison_variants(scenario, "strategies"))
    assert not schedules_identical(qs, dyn)
    # The quasi-static re-timing ends 1.4 s later (scenario description).
    assert qs.t_end - dyn.t_end == pytest.approx(1.4, abs=1e-9)


@pytest.mark.parametrize("text", [SHORT_TURN, TURN_THEN_PICK], ids=["locomotion", "no-overlap"])
def test_schedules_identical_without_overlap(text: str) -> None:
    scenario = load_scenario("<test>", text)
    assert schedules_identical(
        compile_plan(scenario, "quasi-static"), compile_plan(scenario, "dynamic")
    )


def test_identity_is_about_times() -> None:
    a = load_scenario("<test>", SHORT_TURN)
    b = load_scenario("<test>", SHORT_TURN.replace("start: 0.2", "start: 0.3"))
    assert not schedules_identical(compile_plan(a), compile_plan(b))
