"""The side-by-side table: both runs, the difference column (proposed - baseline), errors."""

from __future__ import annotations

from dataclasses import replace

from compare_fixtures import repo_scenario_text, synthetic_comparison
from rich.console import Console

from locoplan.compare import Comparison
from locoplan.report.compare_table import compare_table


def _text(comparison: Comparison) -> str:
    console = Console(width=200, record=True, color_system=None)
    console.print(compare_table(comparison))
    return console.export_text()


def _row(text: str, name: str) -> list[str]:
    """Cells of the first row whose first cell starts with `name` (header rows use ┃)."""
    for raw in text.splitlines():
        line = raw.replace("┃", "│").strip()
        if line.startswith("│") and line.strip("│ ").startswith(name):
            return [c.strip() for c in line.strip("│").split("│")]
    raise AssertionError(f"no row {name!r} in\n{text}")


def test_columns_and_difference_of_strategies() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    text = _text(synthetic_comparison(scenario))
    header = _row(text, "metric")
    assert header == ["metric", "quasi-static", "dynamic", "Δ"]
    assert "Δ = dynamic − quasi-static" in text
    # Synthetic runs end at the plans' ends: 6.0 s and 4.6 s; yaw differences 90 and ~17 deg
    # (the planned trunk yaw at the pick's lift-off and the drop's release).
    assert _row(text, "completion time") == [
        "completion time",
        "6.000 s",
        "4.600 s",
        "-1.400 s",
    ]
    yaw = _row(text, "yaw difference")
    assert yaw[1] == "90.0°" and -80.0 < float(yaw[3].rstrip("°")) < -60.0
    assert _row(text, "peak torque ratio")[1] == "0.60 (L_knee)"
    assert "package on conveyor" in _row(text, "placed")[1]
    for name in ("fell", "MPC update p99", "real-time factor", "expectations"):
        assert _row(text, name)


def test_models_difference_is_external_force_minus_combined() -> None:
    scenario, _ = repo_scenario_text("model-comparison")
    text = _text(synthetic_comparison(scenario, "models"))
    assert _row(text, "metric") == ["metric", "external-force", "combined", "Δ"]
    assert "Δ = external-force − combined" in text


def test_fall_and_broken_run_are_shown() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    comparison = synthetic_comparison(scenario, fall_at=3.0)
    text = _text(comparison)
    assert _row(text, "fell")[1] == "yes (t=3.00 s)"
    assert _row(text, "completion time")[3] == "-"  # no difference without both times
    qs, dyn = comparison.outcomes
    broken = replace(qs, metrics=None, trace=None, error="MPC QP failed at t=1.000 s")
    text = _text(replace(comparison, outcomes=(broken, dyn)))
    assert "run broke: MPC QP failed at t=1.000 s" in text
    assert comparison.to_json()["quasi-static"]["fell"] is True
    as_json = replace(comparison, outcomes=(broken, dyn)).to_json()
    assert as_json["quasi-static"]["error"].startswith("MPC QP failed")
    assert as_json["quasi-static"]["passed"] is False
    assert list(as_json) == ["quasi-static", "dynamic"]
