"""The paper's experiments and their checks: the checks read the metrics and traces right
(synthetic runs that follow the plan), a broken setup is a result, not an exception."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from compare_fixtures import repo_scenario_text, synthetic_comparison

from locoplan.report.results_experiments import (
    EXPERIMENTS,
    Check,
    ExperimentResult,
    experiment_checks,
    held_pitch_deg,
    run_experiment,
    verdict,
)

SCENARIO_DIR = Path(__file__).resolve().parent.parent / "scenarios"


def test_five_experiments_with_existing_scripts() -> None:
    keys = [e.key for e in EXPERIMENTS]
    assert keys == [
        "package-transfer",
        "standing-load",
        "model-comparison",
        "pick-walk-drop",
        "throw",
    ]
    for e in EXPERIMENTS:
        assert (SCENARIO_DIR / e.scenario_file).is_file()
        assert e.paper_claims and e.figures
        assert e.command.startswith("locoplan ")


def _by_what(checks: list[Check]) -> dict[str, Check]:
    return {c.what: c for c in checks}


def test_package_transfer_checks_of_the_planned_motion() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    c = synthetic_comparison(scenario)
    checks = _by_what(experiment_checks("package-transfer", c.outcomes, c, scenario))
    # Runs that follow the plans end 1.4 s apart and differ by 90 - 16.9 = 73.1 deg of yaw.
    assert checks["dynamic finishes sooner by"].ok
    assert checks["dynamic finishes sooner by"].ours.startswith("1.40 s")
    assert checks["pick→drop yaw difference smaller by"].ok
    assert checks["pick→drop yaw difference smaller by"].ours.startswith("73.")
    assert checks["package on the conveyor (dynamic)"].ok
    assert checks["stays up (quasi-static)"].ok


def test_package_transfer_checks_after_a_fall() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    c = synthetic_comparison(scenario, fall_at=3.0)
    checks = _by_what(experiment_checks("package-transfer", c.outcomes, c, scenario))
    assert checks["dynamic finishes sooner by"].ok is False
    yaw = checks["pick→drop yaw difference smaller by"]
    assert yaw.ok is False and "quasi-static did not reach the drop start" in yaw.ours
    assert checks["stays up (quasi-static)"].ours == "fell at 3.00 s"


def test_model_comparison_checks() -> None:
    scenario, _ = repo_scenario_text("model-comparison")
    c = synthetic_comparison(scenario, "models")
    checks = _by_what(experiment_checks("model-comparison", c.outcomes, c, scenario))
    # The synthetic trunk pitches 0.02 rad forward: "leans back" does not hold.
    lean = checks["Model 2 leans back while holding (mean pitch)"]
    assert lean.ok is False and lean.ours == "+1.1°"
    assert checks["Model 1 (combined) falls forward"].ok is False  # it stays up


def test_held_pitch_needs_a_hold() -> None:
    scenario, _ = repo_scenario_text("model-comparison")
    tr = synthetic_comparison(scenario, "models").outcomes[0].trace
    assert tr is not None
    assert held_pitch_deg(tr) == pytest.approx(1.146, abs=1e-3)  # 0.02 rad
    assert held_pitch_deg(None) is None
    assert held_pitch_deg(replace(tr, object_held=tr.object_held & False)) is None


def test_other_keys_get_generic_checks() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    c = synthetic_comparison(scenario)
    whats = [x.what for x in experiment_checks("custom", c.outcomes, None, scenario)]
    assert whats == [
        "stays up (quasi-static)",
        "torques within limits (quasi-static)",
        "stays up (dynamic)",
        "torques within limits (dynamic)",
    ]


def test_verdicts() -> None:
    exp = EXPERIMENTS[0]

    def result(*oks: bool | None, error: str | None = None) -> ExperimentResult:
        checks = tuple(Check(str(i), "", "", ok) for i, ok in enumerate(oks))
        return ExperimentResult(exp, (), None, checks, (), error)

    assert verdict(result(True, None, True)) == "reproduced"
    assert verdict(result(True, False)) == "partly"
    assert verdict(result(False, None)) == "not reproduced"
    assert verdict(result(error="boom")) == "error"


def test_missing_script_is_an_error_result(tmp_path: Path) -> None:
    r = run_experiment(EXPERIMENTS[1], tmp_path, tmp_path / "fig", tmp_path / "runs")
    assert r.error is not None and "standing-load.yaml" in r.error
    assert r.outcomes == () and r.plots == ()
