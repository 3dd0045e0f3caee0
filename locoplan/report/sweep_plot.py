"""PNG plot of a sweep: one metric over the swept key(s).

One key: the metric as a line over the key's values. Two keys: a heat map over the grid (first
key across, second key up). More keys: the metric over the point index, labelled. Points where
the robot fell are marked with a red x, points whose expectations failed (without a fall) with
an orange circle, points where some task's goal was never met (without a fall; a pick that
did not lift its object) with a purple triangle; points without metrics (invalid, broken run)
are grey. For
`peak_torque_ratio` the torque limit (ratio 1) is drawn.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D


def _as_float(value: Any) -> float:
    if value is None or isinstance(value, str):
        return float("nan")
    return float(value)


def _label(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def _legend_handles(
    any_fell: bool, any_failed: bool, any_incomplete: bool, any_missing: bool
) -> list[Line2D]:
    handles = []
    if any_fell:
        handles.append(
            Line2D([], [], color="red", marker="x", linestyle="", markersize=9, label="fell")
        )
    if any_failed:
        handles.append(
            Line2D([], [], color="darkorange", marker="o", markerfacecolor="none",
                   linestyle="", markersize=10, label="expectation failed")
        )  # fmt: skip
    if any_incomplete:
        handles.append(
            Line2D([], [], color="purple", marker="v", linestyle="", markersize=7,
                   label="task not completed")
        )  # fmt: skip
    if any_missing:
        handles.append(
            Line2D([], [], color="grey", alpha=0.4, linewidth=3, label="no result (error)")
        )
    return handles


def plot_sweep(
    rows: Sequence[Mapping[str, Any]],
    keys: Sequence[str],
    metric: str,
    path: str | Path,
    title: str = "",
) -> None:
    """Draw `metric` of `rows` (from `locoplan.batch.sweep.sweep_rows`) over `keys` to `path`
    (PNG). Raises OSError when the file cannot be written, ValueError without keys."""
    if not keys:
        raise ValueError("a sweep plot needs at least one key")
    y = np.array([_as_float(r.get(metric)) for r in rows])
    fell = np.array([bool(r.get("fell")) for r in rows])
    failed = np.array([r.get("passed") is False and not r.get("fell") for r in rows])
    incomplete = np.array([r.get("completed") is False and not r.get("fell") for r in rows])
    missing = np.array([r.get(metric) is None for r in rows])
    fig = Figure(figsize=(8, 5), dpi=110)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    if len(keys) == 2:
        _heat_map(fig, ax, rows, keys, metric, y, fell, failed, incomplete)
    else:
        _line(ax, rows, keys, metric, y, fell, failed, incomplete, missing)
    handles = _legend_handles(
        bool(fell.any()), bool(failed.any()), bool(incomplete.any()), bool(missing.any())
    )
    if handles:
        # Below the axes: inside, it would hide a heat-map cell or a point of the line.
        ax.legend(
            handles=handles,
            loc="upper center",
            bbox_to_anchor=(0.5, -0.18),
            ncol=len(handles),
            fontsize=8,
            frameon=False,
        )
    ax.set_title(title or f"{metric} over {' x '.join(keys)}")
    fig.tight_layout()
    fig.savefig(path)


def _line(
    ax: Any,
    rows: Sequence[Mapping[str, Any]],
    keys: Sequence[str],
    metric: str,
    y: np.ndarray,
    fell: np.ndarray,
    failed: np.ndarray,
    incomplete: np.ndarray,
    missing: np.ndarray,
) -> None:
    if len(keys) == 1 and all(isinstance(r[keys[0]], int | float) for r in rows):
        x = np.array([float(r[keys[0]]) for r in rows])
        ax.set_xlabel(keys[0])
    else:
        x = np.arange(len(rows), dtype=float)
        labels = [",".join(_label(r[k]) for k in keys) for r in rows]
        ax.set_xticks(x, labels, rotation=45, ha="right", fontsize=7)
        ax.set_xlabel(", ".join(keys))
    ax.plot(x, y, "-o", color="tab:blue", markersize=4)
    ax.plot(x[fell], y[fell], "x", color="red", markersize=9, mew=2)
    ax.plot(x[failed], y[failed], "o", color="darkorange", markersize=10, mfc="none", mew=1.5)
    ax.plot(x[incomplete], y[incomplete], "v", color="purple", markersize=7)
    if missing.any():
        for xm in x[missing]:
            ax.axvline(xm, color="grey", alpha=0.4, linewidth=3)
    if metric == "peak_torque_ratio":
        ax.axhline(1.0, color="red", linestyle="--", linewidth=1)
    ax.set_ylabel(metric)
    ax.grid(True, alpha=0.3)


def _heat_map(
    fig: Any,
    ax: Any,
    rows: Sequence[Mapping[str, Any]],
    keys: Sequence[str],
    metric: str,
    y: np.ndarray,
    fell: np.ndarray,
    failed: np.ndarray,
    incomplete: np.ndarray,
) -> None:
    xs = list(dict.fromkeys(r[keys[0]] for r in rows))
    ys = list(dict.fromkeys(r[keys[1]] for r in rows))
    grid = np.full((len(ys), len(xs)), np.nan)
    col = [xs.index(r[keys[0]]) for r in rows]
    row = [ys.index(r[keys[1]]) for r in rows]
    grid[row, col] = y
    cmap = matplotlib.colormaps["viridis"].with_extremes(bad="lightgrey")
    image = ax.imshow(np.ma.masked_invalid(grid), origin="lower", aspect="auto", cmap=cmap)
    fig.colorbar(image, ax=ax, label=metric)
    ax.set_xticks(range(len(xs)), [_label(v) for v in xs], rotation=45, ha="right")
    ax.set_yticks(range(len(ys)), [_label(v) for v in ys])
    ax.set_xlabel(keys[0])
    ax.set_ylabel(keys[1])
    c, r = np.array(col), np.array(row)
    ax.plot(c[fell], r[fell], "x", color="red", markersize=10, mew=2)
    ax.plot(c[failed], r[failed], "o", color="darkorange", markersize=12, mfc="none", mew=1.5)
    ax.plot(c[incomplete], r[incomplete], "v", color="purple", markersize=8)
