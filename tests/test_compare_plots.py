"""Comparison plots: every figure carries one series per run (checked on the matplotlib
objects before saving), the files are real PNGs of a readable size. Synthetic traces that
follow the plan keep these tests free of simulation."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from compare_fixtures import repo_scenario_text, synthetic_comparison, synthetic_trace
from matplotlib.figure import Figure

from locoplan.compare import RunTrace, fixture_outlines
from locoplan.report.compare_plots import (
    FILE_NAMES,
    PLOT_KINDS,
    build_figure,
    contact_figure,
    paths_figure,
    pitch_figure,
    plot_comparison,
    plot_traces,
    png_size,
    torque_figure,
    trunk_shift,
    yaw_figure,
)
from locoplan.scenario import Scenario

PackageTraces = tuple[Scenario, list[RunTrace]]
MIN_PNG_BYTES = 15_000  # a blank 1000x500 PNG is ~5 kB; curves, text and legends add more
MIN_SIDE_PX = 500  # readable in a report page at 100 dpi


def _line_labels(fig: Figure) -> set[str]:
    return {str(line.get_label()) for ax in fig.axes for line in ax.get_lines()}


@pytest.fixture(scope="module")
def package_traces() -> PackageTraces:
    scenario, _ = repo_scenario_text("package-transfer")
    return scenario, [
        synthetic_trace(scenario, "quasi-static", "quasi-static"),
        synthetic_trace(scenario, "dynamic", "dynamic"),
    ]


def test_yaw_figure_has_both_runs_marks_and_annotation(package_traces: PackageTraces) -> None:
    _, traces = package_traces
    fig = yaw_figure(traces)
    labels = _line_labels(fig)
    for run in ("quasi-static", "dynamic"):
        assert {run, f"{run} plan", f"{run} pick start", f"{run} drop start"} <= labels
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    # The plan turns 90 deg between the quasi-static pick and drop starts; the dynamic plan
    # about 17 deg (scenario description). Annotations carry one decimal.
    assert "Δyaw 90.0°" in texts
    assert any(t.startswith("Δyaw 1") for t in texts)
    assert "quasi-static 90.0°" in fig.axes[0].get_title()


def test_yaw_figure_says_when_the_drop_was_not_reached() -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    fallen = synthetic_trace(scenario, "quasi-static", "quasi-static", fall_at=3.0)
    assert fallen.yaw_difference_deg is None  # the drop starts at 4.2 s, after the fall
    fig = yaw_figure([fallen])
    assert "not reached" in fig.axes[0].get_title()
    assert "quasi-static fell" in _line_labels(fig)


def test_contact_figure_rows_for_both_runs(package_traces: PackageTraces) -> None:
    _, traces = package_traces
    fig = contact_figure(traces)
    ticks = [t.get_text() for t in fig.axes[0].get_yticklabels()]
    for run in ("quasi-static", "dynamic"):
        for row in (
            "L foot stance",
            "R foot stance",
            "L hand contact",
            "R hand contact",
            "object held",
            "package lifted (sim)",
        ):
            assert f"{run}: {row}" in ticks
    # Broken bars exist for stance, hand contact and the hold of each run.
    assert len(fig.axes[0].collections) >= 2 * 5


def test_torque_figure_one_axis_per_left_leg_joint_with_limits(
    package_traces: PackageTraces,
) -> None:
    _, traces = package_traces
    fig = torque_figure(traces)
    axes = [ax for ax in fig.axes if ax.get_ylabel()]
    names = [ax.get_ylabel().split("\n")[0] for ax in axes]
    assert names == ["L_hip_yaw", "L_hip_roll", "L_hip_pitch", "L_knee", "L_ankle"]
    for ax in axes:
        labels = {str(line.get_label()) for line in ax.get_lines()}
        assert {"quasi-static", "dynamic"} <= labels
        assert any(label.startswith("limit ±") for label in labels)
    knee = axes[3]
    assert any(str(line.get_label()) == "limit ±67 N m" for line in knee.get_lines())


def test_paths_figure_trunk_object_and_target(package_traces: PackageTraces) -> None:
    scenario, traces = package_traces
    fig = paths_figure(traces, fixture_outlines(scenario))
    labels = _line_labels(fig)
    for run in ("quasi-static", "dynamic"):
        assert {f"{run} trunk", f"{run} package", f"{run} package target (plan)"} <= labels
    top = fig.axes[0]
    assert len(top.patches) == len(scenario.fixtures)  # table and conveyor outlines


def test_pitch_figure_both_runs(package_traces: PackageTraces) -> None:
    _, traces = package_traces
    assert {"quasi-static", "dynamic"} <= _line_labels(pitch_figure(traces))


def test_every_kind_written_as_png(tmp_path: Path) -> None:
    scenario, _ = repo_scenario_text("package-transfer")
    comparison = synthetic_comparison(scenario)
    files = plot_comparison(comparison, tmp_path)
    assert [f.kind for f in files] == list(PLOT_KINDS)
    for f in files:
        assert f.path == tmp_path / FILE_NAMES[f.kind]
        assert f.path.stat().st_size > MIN_PNG_BYTES
        assert png_size(f.path) == (f.width_px, f.height_px)
        assert min(f.width_px, f.height_px) >= MIN_SIDE_PX
        assert f.series == ("quasi-static", "dynamic")


def test_models_comparison_plots_label_the_models(tmp_path: Path) -> None:
    scenario, _ = repo_scenario_text("model-comparison")
    comparison = synthetic_comparison(scenario, "models")
    files = plot_comparison(comparison, tmp_path, prefix="m-")
    assert all(f.path.name.startswith("m-") for f in files)
    traces = [o.trace for o in comparison.outcomes if o.trace is not None]
    assert {"external-force", "combined"} <= _line_labels(pitch_figure(traces))


def test_nothing_drawn_without_traces(tmp_path: Path) -> None:
    assert plot_traces([], tmp_path) == ()
    with pytest.raises(ValueError, match="no run"):
        build_figure("yaw", [])


def test_unknown_kind_rejected(package_traces: PackageTraces) -> None:
    _, traces = package_traces
    with pytest.raises(ValueError, match="unknown plot kind"):
        build_figure("snapshots", traces)


def test_png_size_rejects_other_files(tmp_path: Path) -> None:
    p = tmp_path / "x.png"
    p.write_bytes(b"GIF89a" + bytes(30))
    with pytest.raises(ValueError, match="not a PNG"):
        png_size(p)


def test_trunk_shift_is_along_the_start_heading(package_traces: PackageTraces) -> None:
    _, traces = package_traces
    tr = traces[0]
    n = tr.t.size
    # Facing +y (yaw 90 deg) and moving 5 cm towards -y is 5 cm back; sideways motion is not
    # counted. Exact up to float rounding of cos(pi/2).
    rpy = np.zeros((n, 3))
    rpy[:, 2] = np.pi / 2
    pos = np.zeros((n, 3))
    pos[:, 1] = np.linspace(0.0, -0.05, n)
    pos[:, 0] = np.linspace(0.0, 0.30, n)
    shift = trunk_shift(replace(tr, base_rpy=rpy, base_position=pos))
    assert shift[0] == 0.0
    assert shift[-1] == pytest.approx(-0.05, abs=1e-12)
    assert len(pitch_figure(traces).axes) == 3
