"""docs/results.md rendering: every experiment has the paper's claims, our checks and our
plots (links that resolve), failures are written down, and a closed-loop build runs end to
end even when one experiment cannot run."""

from __future__ import annotations

import datetime
import re
from dataclasses import replace
from pathlib import Path

import pytest
from compare_fixtures import SHORT_STAND, repo_scenario_text, synthetic_comparison

from locoplan.report.compare_plots import plot_comparison
from locoplan.report.results_doc import render_results, write_results
from locoplan.report.results_experiments import (
    EXPERIMENTS,
    Experiment,
    ExperimentResult,
    experiment_checks,
)

WHEN = datetime.datetime(2025, 1, 2, 3, 4, tzinfo=datetime.UTC)


def _links(markdown: str) -> list[str]:
    return re.findall(r"!\[[^\]]*\]\(([^)]+)\)", markdown)


def test_render_reports_checks_plots_and_errors(tmp_path: Path) -> None:
    doc_dir, scenarios = tmp_path / "docs", tmp_path / "scenarios"
    scenario, _ = repo_scenario_text("package-transfer")
    c = synthetic_comparison(scenario)
    plots = plot_comparison(c, doc_dir / "results" / "package-transfer")
    pt = ExperimentResult(
        EXPERIMENTS[0],
        c.outcomes,
        c,
        tuple(experiment_checks("package-transfer", c.outcomes, c, scenario)),
        plots,
    )
    broken = ExperimentResult(EXPERIMENTS[4], (), None, (), (), "TypeError: something broke")
    text = render_results([pt, broken], doc_dir, scenarios, revision="abc123", generated=WHEN)
    assert text.startswith("# Results: the paper's experiments, reproduced")
    assert "2025-01-02 03:04 UTC" in text and "`abc123`" in text
    assert "## 1. Package transfer" in text and "## 2. Pick a 2 kg ball" in text
    assert "1.7 s sooner" in text and "up to 30° smaller" in text  # the paper's words
    assert "| dynamic finishes sooner by | 1.7 s | 1.40 s" in text
    assert "✅ reproduced" in text
    assert "❌ could not run" in text and "TypeError: something broke" in text
    assert "[`../scenarios/package-transfer.yaml`](../scenarios/package-transfer.yaml)" in text
    links = _links(text)
    assert len(links) == 4  # paths, yaw, torque, contacts (the experiment's figures)
    for link in links:
        assert (doc_dir / link).is_file(), link
    # Summary table anchors point at the section headings (GitHub's slug rule).
    assert "(#1-package-transfer-turn-90-pick-3-kg-turn--90-drop-on-a-conveyor)" in text


def test_a_broken_run_is_written_down(tmp_path: Path) -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    c = synthetic_comparison(scenario)
    qs, dyn = c.outcomes
    broke = replace(qs, metrics=None, trace=None, error="WBC QP failed at t=2.000 s")
    c = replace(c, outcomes=(broke, dyn))
    r = ExperimentResult(
        EXPERIMENTS[0],
        c.outcomes,
        c,
        tuple(experiment_checks("package-transfer", c.outcomes, c, scenario)),
        (),
    )
    text = render_results([r], tmp_path, tmp_path)
    assert "> The quasi-static run broke: WBC QP failed at t=2.000 s" in text
    assert "| quasi-static | run broke: WBC QP failed" in text
    assert "no plot (no run produced data)" in text


@pytest.mark.closed_loop
def test_build_runs_end_to_end_when_an_experiment_cannot_run(tmp_path: Path) -> None:
    scenarios = tmp_path / "scenarios"
    scenarios.mkdir()
    (scenarios / "short-stand.yaml").write_text(SHORT_STAND)
    ok = Experiment(
        "short-stand",
        "Stand for a second",
        "short-stand.yaml",
        "single",
        ("Stands.",),
        (("pitch", "No figure."), ("torque", "No figure.")),
        "locoplan run short-stand.yaml",
    )
    missing = replace(ok, key="missing", title="A missing script", scenario_file="nope.yaml")
    doc = tmp_path / "docs" / "results.md"
    done: list[str] = []
    results = write_results(
        scenarios,
        doc,
        tmp_path / "docs" / "results",
        tmp_path / "runs",
        experiments=[ok, missing],
        done=lambda r: done.append(r.experiment.key),
    )
    assert done == ["short-stand", "missing"]
    assert results[0].error is None and results[0].outcomes[0].passed
    assert results[1].error is not None
    text = doc.read_text()
    assert "## 1. Stand for a second" in text and "✅ reproduced" in text
    assert "## 2. A missing script" in text and "could not run" in text
    for link in _links(text):
        assert (doc.parent / link).is_file()
    assert (tmp_path / "runs" / "short-stand" / "short-stand.mcap").is_file()
