"""Side-by-side runs of one task script: quasi-static vs dynamic, or Model 1 vs Model 2.

Entry point: `compare_scenario(scenario, text, out_dir, kind="strategies" | "models", ...)`
-> `Comparison`; `write_compare_json` writes compare.json. Plots and tables of a comparison
live in `locoplan.report.compare_plots` and `locoplan.report.compare_table`.
"""

from locoplan.compare.comparison import (
    DIFFERENCE_KEYS,
    Comparison,
    compare_scenario,
    write_compare_json,
)
from locoplan.compare.runner import VariantOutcome, default_jobs, run_variants
from locoplan.compare.trace import FixtureOutline, RunTrace, TaskWindow, fixture_outlines
from locoplan.compare.variants import (
    MODELS,
    CompareKind,
    Variant,
    baseline_and_proposed,
    comparison_variants,
    schedules_identical,
)

__all__ = [
    "DIFFERENCE_KEYS",
    "MODELS",
    "CompareKind",
    "Comparison",
    "FixtureOutline",
    "RunTrace",
    "TaskWindow",
    "Variant",
    "VariantOutcome",
    "baseline_and_proposed",
    "compare_scenario",
    "comparison_variants",
    "default_jobs",
    "fixture_outlines",
    "run_variants",
    "schedules_identical",
    "write_compare_json",
]
