"""Plots of one or more runs side by side (`locoplan compare`, `make results`).

Each `*_figure` function builds a matplotlib `Figure` on the Agg canvas (no pyplot, no global
backend switch) from `RunTrace`s, one series per run with the run's label, so callers and
tests can inspect the figure before `save_figure` writes it:

- `yaw_figure`: trunk yaw over time, measured and planned, with pick-start and drop-start
  marked and the pick-to-drop yaw difference annotated (the paper's Fig. 90-turn measure);
- `contact_figure`: the contact timeline of every run on one time axis (feet stance, hand
  contact, object held as planned, object off its support as simulated);
- `torque_figure`: each leg joint's applied torque over time against its limit band (the
  paper's torque figure, left leg by default);
- `paths_figure`: top view of the trunk and object paths over the fixtures, with the robot's
  heading at the pick and drop starts, and the objects' height over time;
- `pitch_figure`: trunk pitch (lean) and height over time (the model comparison).
"""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Patch, Polygon

from locoplan.compare.comparison import Comparison
from locoplan.compare.trace import FixtureOutline, RunTrace

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

PLOT_KINDS = ("yaw", "contacts", "torque", "paths", "pitch")
FILE_NAMES = {
    "yaw": "yaw.png",
    "contacts": "contacts.png",
    "torque": "torque-left-leg.png",
    "paths": "paths.png",
    "pitch": "pitch.png",
}
_COLORS = {
    "quasi-static": "#e8710a",
    "dynamic": "#1967d2",
    "external-force": "#1967d2",
    "combined": "#c5221f",
}
_CYCLE = ("#1967d2", "#e8710a", "#188038", "#9334e6", "#c5221f")
_FIXTURE_COLORS = {"table": "#d7ccc8", "conveyor": "#cfd8dc", "platform": "#dcedc8"}


@dataclass(frozen=True, slots=True)
class PlotFile:
    """A PNG written by `save_figure`: its path, what it shows (one of PLOT_KINDS), the run
    labels drawn in it, and its size in pixels."""

    path: Path
    kind: str
    series: tuple[str, ...]
    width_px: int
    height_px: int


def color_of(label: str, index: int = 0) -> str:
    """The colour a run label is drawn in (fixed for the four known labels)."""
    return _COLORS.get(label, _CYCLE[index % len(_CYCLE)])


def _new_figure(width: float, height: float) -> Figure:
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _runs(t: FloatArray, flags: BoolArray) -> list[tuple[float, float]]:
    """(start, width) of each run of True in `flags` sampled at `t` (s); each sample covers
    until the next one (the last one a median sample period)."""
    if t.size == 0:
        return []
    dt = float(np.median(np.diff(t))) if t.size > 1 else 0.01
    f = np.asarray(flags, dtype=np.int8)
    edges = np.diff(np.concatenate(([0], f, [0])))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    out = []
    for a, b in zip(starts, ends, strict=True):
        t0 = float(t[a])
        t1 = float(t[b]) if b < t.size else float(t[-1]) + dt
        out.append((t0, t1 - t0))
    return out


def _t_max(traces: Sequence[RunTrace]) -> float:
    return max([tr.t_end for tr in traces] + [float(tr.t[-1]) for tr in traces if tr.t.size])


def _mark_fall(ax: Axes, tr: RunTrace, y: float, color: str) -> None:
    if tr.fall_time is not None:
        ax.plot([tr.fall_time], [y], "x", color=color, ms=9, mew=2, label=f"{tr.label} fell")


# --- yaw ------------------------------------------------------------------------------------


def yaw_figure(traces: Sequence[RunTrace], title: str | None = None) -> Figure:
    """Trunk yaw (deg) over time for every run: measured (solid, labelled with the run's
    label) and planned (dashed, "<label> plan"); pick start (dotted) and drop/throw start
    (dash-dot) per run, with the measured yaw difference between them drawn as a bracket."""
    fig = _new_figure(10.0, 5.2)
    ax = fig.add_subplot()
    parts = []
    for k, tr in enumerate(traces):
        c = color_of(tr.label, k)
        yaw = np.degrees(tr.yaw)
        ax.plot(tr.t, yaw, color=c, lw=2.0, label=tr.label)
        ax.plot(
            tr.t,
            np.degrees(tr.yaw_reference),
            color=c,
            lw=1.0,
            ls="--",
            alpha=0.7,
            label=f"{tr.label} plan",
        )
        if tr.fall_time is not None and tr.t.size:
            _mark_fall(ax, tr, math.degrees(tr.yaw_at(tr.fall_time)), c)
        if tr.pick_start is None or tr.drop_start is None:
            continue
        ax.axvline(tr.pick_start, color=c, ls=":", lw=1.3, label=f"{tr.label} pick start")
        ax.axvline(
            tr.drop_start, color=c, ls="-.", lw=1.3, label=f"{tr.label} {tr.release_kind} start"
        )
        d = tr.yaw_difference_deg
        if d is None:
            parts.append(f"{tr.label} not reached (run ended at {float(tr.t[-1]):.2f} s)")
            continue
        y_pick = math.degrees(tr.yaw_at(tr.pick_start))
        y_drop = math.degrees(tr.yaw_at(tr.drop_start))
        ax.plot([tr.pick_start, tr.drop_start], [y_pick, y_drop], "o", color=c, ms=6)
        # Bracket at the drop start from the yaw at the pick start to the yaw at the drop.
        ax.plot([tr.pick_start, tr.drop_start], [y_pick, y_pick], color=c, ls=":", lw=1.0)
        ax.annotate(
            "",
            xy=(tr.drop_start, y_drop),
            xytext=(tr.drop_start, y_pick),
            arrowprops={"arrowstyle": "<->", "color": c, "lw": 1.6},
        )
        ax.annotate(
            f"Δyaw {d:.1f}°",
            xy=(tr.drop_start, 0.5 * (y_pick + y_drop)),
            xytext=(6, 0),
            textcoords="offset points",
            color=c,
            fontsize=10,
            fontweight="bold",
            va="center",
        )
        parts.append(f"{tr.label} {d:.1f}°")
    ax.set_xlim(0.0, _t_max(traces))
    ax.set_xlabel("time (s)")
    ax.set_ylabel("trunk yaw (deg)")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
    head = title or "Trunk yaw"
    ax.set_title(head + (f"\nΔyaw pick start → drop start: {'; '.join(parts)}" if parts else ""))
    return fig


# --- contacts -------------------------------------------------------------------------------


def contact_figure(traces: Sequence[RunTrace], title: str | None = None) -> Figure:
    """Contact timeline of every run on one time axis. Per run, rows (labelled "<label>: ..."):
    L foot / R foot stance, L hand / R hand contact, object held (all as planned) and, per
    object, whether the simulation has it off its support ("lifted (sim)")."""
    n_rows = sum(5 + len(tr.object_lifted) for tr in traces)
    fig = _new_figure(11.0, 1.2 + 0.32 * n_rows + 0.3 * len(traces))
    ax = fig.add_subplot()
    labels: list[str] = []
    h = 0.7
    kinds = {
        "foot": "#81c995",
        "hand": "#669df6",
        "held": "#af5cf7",
        "lifted": "#f6aea9",
    }
    for k, tr in enumerate(traces):
        c = color_of(tr.label, k)
        rows: list[tuple[str, FloatArray, BoolArray, str]] = [
            ("L foot stance", tr.t_plan, tr.feet_stance[:, 0], kinds["foot"]),
            ("R foot stance", tr.t_plan, tr.feet_stance[:, 1], kinds["foot"]),
            ("L hand contact", tr.t_plan, tr.hands_contact[:, 0], kinds["hand"]),
            ("R hand contact", tr.t_plan, tr.hands_contact[:, 1], kinds["hand"]),
            ("object held", tr.t_plan, tr.object_held, kinds["held"]),
        ]
        rows += [
            (f"{name} lifted (sim)", tr.t, f, kinds["lifted"])
            for name, f in tr.object_lifted.items()
        ]
        top = -len(labels) - 1
        for name, times, flags, color in rows:
            labels.append(f"{tr.label}: {name}")
            y = -float(len(labels))
            ax.broken_barh(_runs(times, flags), (y - h / 2, h), color=color)
        bottom = -float(len(labels))
        for when, ls in ((tr.pick_start, ":"), (tr.drop_start, "-.")):
            if when is not None:
                ax.plot([when, when], [top + 0.5, bottom - 0.5], color=c, ls=ls, lw=1.5)
        if tr.fall_time is not None:
            # The plan goes on after a fall; grey out what the robot never got to do.
            ax.plot([tr.fall_time] * 2, [top + 0.5, bottom - 0.5], color="black", lw=2.0)
            ax.fill_between(
                [tr.fall_time, tr.t_end],
                top + 0.5,
                bottom - 0.5,
                color="white",
                alpha=0.6,
                hatch="//",
                edgecolor="0.5",
                lw=0,
                zorder=3,
            )
            ax.text(
                tr.fall_time,
                top + 0.3,
                f" {tr.label} fell at {tr.fall_time:.2f} s",
                va="top",
                fontsize=8,
                zorder=4,
            )
        ax.axhspan(bottom - 0.5, top + 0.5, color=c, alpha=0.06, lw=0)
        ax.axhline(bottom - 0.5, color="0.6", lw=0.8)
    ax.set_yticks([-(i + 1) for i in range(len(labels))], labels)
    for tick, text in zip(ax.get_yticklabels(), labels, strict=True):
        tick.set_color(color_of(text.split(":")[0], 0))
    ax.set_ylim(-len(labels) - 0.6, -0.4)
    ax.set_xlim(0.0, _t_max(traces))
    ax.set_xlabel("time (s)")
    ax.grid(axis="x", alpha=0.3)
    ax.legend(
        handles=[
            Patch(color=kinds["foot"], label="foot in stance (plan)"),
            Patch(color=kinds["hand"], label="hand in contact (plan)"),
            Patch(color=kinds["held"], label="object held (plan, σe)"),
            Patch(color=kinds["lifted"], label="object off its support (sim)"),
        ],
        loc="upper left",
        bbox_to_anchor=(1.0, 1.0),
        fontsize=8,
        title="dotted: pick start\ndash-dot: drop start",
        title_fontsize=8,
    )
    ax.set_title(title or "Contact timeline")
    return fig


# --- torques --------------------------------------------------------------------------------


def torque_figure(traces: Sequence[RunTrace], side: int = 0, title: str | None = None) -> Figure:
    """Each leg joint's applied torque (N m) over time on its own axes, one line per run
    (labelled with the run's label), against the joint's limit band ±tau_max (grey, with the
    limit drawn dashed). `side` 0 left leg (the paper's figure), 1 right leg."""
    names = traces[0].leg_joints[side]
    fig = _new_figure(10.0, 1.1 + 1.55 * len(names))
    axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
    for ax, name in zip(axes, names, strict=True):
        j = traces[0].joint_names.index(name)
        limit = float(traces[0].torque_limits[j])
        ax.axhspan(-limit, limit, color="0.92", lw=0)
        ax.axhline(limit, color="0.35", ls="--", lw=1.0, label=f"limit ±{limit:g} N m")
        ax.axhline(-limit, color="0.35", ls="--", lw=1.0)
        peak_text = []
        for k, tr in enumerate(traces):
            if not tr.t.size:
                continue
            tau = tr.joint_torque[:, tr.joint_names.index(name)]
            ax.plot(tr.t[: tau.size], tau, color=color_of(tr.label, k), lw=1.2, label=tr.label)
            peak_text.append(f"{tr.label} {np.max(np.abs(tau)) / limit:.2f}")
        ax.set_ylim(-1.15 * limit, 1.15 * limit)
        ax.set_ylabel(f"{name}\n(N m)", fontsize=9)
        ax.grid(alpha=0.3)
        ax.set_title(
            "peak of sampled |τ| / limit: " + ", ".join(peak_text), loc="right", fontsize=8, pad=2
        )
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize=8)
    axes[-1].set_xlabel("time (s)")
    axes[-1].set_xlim(0.0, _t_max(traces))
    leg = "left" if side == 0 else "right"
    fig.suptitle(title or f"Torques of the {leg} leg joints against their limits")
    return fig


# --- paths ----------------------------------------------------------------------------------


def _heading(ax: Axes, tr: RunTrace, when: float | None, color: str, ls: str) -> None:
    if when is None or not tr.t.size or when > tr.t[-1] + 1e-9:
        return  # not reached: the run ended (fell) before
    x = float(np.interp(when, tr.t, tr.base_position[:, 0]))
    y = float(np.interp(when, tr.t, tr.base_position[:, 1]))
    yaw = tr.yaw_at(when)
    L = 0.45  # m: long enough to read the direction next to a 0.4 m table
    ax.plot([x, x + L * math.cos(yaw)], [y, y + L * math.sin(yaw)], color=color, ls=ls, lw=1.4)


def paths_figure(
    traces: Sequence[RunTrace], fixtures: Sequence[FixtureOutline] = (), title: str | None = None
) -> Figure:
    """Left: top view (x, y in m, equal axes) of the fixtures, each run's trunk path (solid,
    labelled "<label> trunk") and object paths (dashed, "<label> <object>"), with the trunk's
    heading at the pick start (dotted ray) and drop start (dash-dot ray), like the paper's
    top-view snapshots. Right: each object's height (m) over time."""
    fig = _new_figure(12.0, 5.4)
    ax, ax_h = fig.subplots(1, 2, width_ratios=(1.25, 1.0))
    for f in fixtures:
        ax.add_patch(
            Polygon(
                f.corners(),
                closed=True,
                facecolor=_FIXTURE_COLORS.get(f.kind, "0.85"),
                edgecolor="0.4",
                lw=1.0,
                zorder=0,
            )
        )
        corners = f.corners()
        ax.text(
            float(np.mean(corners[:4, 0])),
            float(np.max(corners[:, 1])) - 0.02,
            f"{f.name} (top {f.top:.2f} m)",
            ha="center",
            va="top",
            fontsize=8,
            color="0.3",
        )
    for k, tr in enumerate(traces):
        c = color_of(tr.label, k)
        if not tr.t.size:
            continue
        p = tr.base_position
        ax.plot(p[:, 0], p[:, 1], color=c, lw=2.0, label=f"{tr.label} trunk")
        ax.plot(p[0, 0], p[0, 1], "o", color=c, ms=5)
        for name, q in tr.object_positions.items():
            ax.plot(q[:, 0], q[:, 1], color=c, ls="--", lw=1.4, label=f"{tr.label} {name}")
            ax.plot(q[-1, 0], q[-1, 1], "s", color=c, ms=6, mfc="white")
            target = tr.object_targets.get(name)
            if target is not None:
                ax.plot(
                    target[0],
                    target[1],
                    "*",
                    color="#f9ab00",
                    mec=c,
                    ms=14,
                    label=f"{tr.label} {name} target (plan)",
                    zorder=5,
                )
            ax_h.plot(tr.t, q[:, 2], color=c, lw=1.6, label=f"{tr.label} {name}")
        _heading(ax, tr, tr.pick_start, c, ":")
        _heading(ax, tr, tr.drop_start, c, "-.")
        if tr.fall_time is not None:
            fx = float(np.interp(tr.fall_time, tr.t, p[:, 0]))
            fy = float(np.interp(tr.fall_time, tr.t, p[:, 1]))
            ax.plot([fx], [fy], "x", color=c, ms=10, mew=2, label=f"{tr.label} fell")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(
        "top view (rays: heading at pick start ··· and drop/throw start -·-; □ object at the end)",
        fontsize=10,
    )
    for f in fixtures:
        ax_h.axhline(f.top, color="0.5", ls=":", lw=1.0)
    ax_h.set_xlim(0.0, _t_max(traces))
    ax_h.set_xlabel("time (s)")
    ax_h.set_ylabel("object centre height (m)")
    ax_h.grid(alpha=0.3)
    if ax_h.get_lines():
        ax_h.legend(loc="best", fontsize=8)
    ax_h.set_title("objects' height (dotted: fixture tops)", fontsize=10)
    fig.suptitle(title or "Trunk and object paths")
    return fig


# --- pitch ----------------------------------------------------------------------------------


def trunk_shift(tr: RunTrace) -> FloatArray:
    """Trunk origin displacement (n,) m along the run's initial heading from its initial
    position (negative: the pelvis moved back, as when leaning back against a load)."""
    if not tr.t.size:
        return np.zeros(0)
    heading = np.array([math.cos(tr.yaw[0]), math.sin(tr.yaw[0])])
    return np.asarray((tr.base_position[:, :2] - tr.base_position[0, :2]) @ heading)


def pitch_figure(traces: Sequence[RunTrace], title: str | None = None) -> Figure:
    """Top: trunk pitch (deg, positive = leaning forward) over time, one line per run
    (labelled with the run's label), with the planned object-held intervals as bars. Middle:
    trunk shift along the initial heading (cm, negative = back). Bottom: trunk height (m),
    where a fall shows as a drop."""
    fig = _new_figure(10.0, 7.0)
    ax, ax_x, ax_z = fig.subplots(3, 1, sharex=True, height_ratios=(1.5, 1.0, 1.0))
    for k, tr in enumerate(traces):
        c = color_of(tr.label, k)
        if not tr.t.size:
            continue
        ax.plot(tr.t, np.degrees(tr.base_rpy[:, 1]), color=c, lw=1.8, label=tr.label)
        ax_x.plot(tr.t, 100.0 * trunk_shift(tr), color=c, lw=1.5, label=tr.label)
        ax_z.plot(tr.t, tr.base_position[:, 2], color=c, lw=1.5, label=tr.label)
        # Held intervals as thin bars along the top edge (x in s, y in axes fraction).
        ax.broken_barh(
            _runs(tr.t_plan, tr.object_held),
            (0.97 - 0.035 * k, 0.025),
            color=c,
            alpha=0.6,
            transform=ax.get_xaxis_transform(),
        )
        if tr.fall_time is not None:
            ax_z.axvline(tr.fall_time, color=c, ls="--", lw=1.0, label=f"{tr.label} fell")
    ax.axhline(0.0, color="0.4", lw=0.8)
    ax.set_ylabel("trunk pitch (deg)\n+ = leaning forward")
    ax.grid(alpha=0.3)
    ax.legend(
        loc="upper left",
        bbox_to_anchor=(1.0, 1.0),
        fontsize=8,
        title="bars at the top: object held (plan)",
        title_fontsize=8,
    )
    ax_x.axhline(0.0, color="0.4", lw=0.8)
    ax_x.set_ylabel("trunk shift along\nstart heading (cm)")
    ax_x.grid(alpha=0.3)
    ax_z.set_ylabel("trunk height (m)")
    ax_z.set_xlabel("time (s)")
    ax_z.grid(alpha=0.3)
    ax_z.set_xlim(0.0, _t_max(traces))
    fig.suptitle(title or "Trunk lean, shift and height")
    return fig


# --- files ----------------------------------------------------------------------------------


def png_size(path: Path) -> tuple[int, int]:
    """(width, height) in pixels from a PNG's IHDR chunk (ValueError if not a PNG)."""
    head = path.read_bytes()[:24]
    if head[:8] != b"\x89PNG\r\n\x1a\n" or head[12:16] != b"IHDR":
        raise ValueError(f"{path} is not a PNG file")
    width, height = struct.unpack(">II", head[16:24])
    return int(width), int(height)


def save_figure(
    fig: Figure, path: Path, kind: str, series: Sequence[str], dpi: int = 100
) -> PlotFile:
    """Write `fig` as a PNG at `path` (parent directories created) and describe it."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    w, h = png_size(path)
    return PlotFile(path, kind, tuple(series), w, h)


def build_figure(
    kind: str,
    traces: Sequence[RunTrace],
    fixtures: Sequence[FixtureOutline] = (),
    title: str | None = None,
) -> Figure:
    """The figure of one of PLOT_KINDS (ValueError for another kind or no traces)."""
    if not traces:
        raise ValueError("nothing to plot: no run produced a trace")
    if kind == "yaw":
        return yaw_figure(traces, title)
    if kind == "contacts":
        return contact_figure(traces, title)
    if kind == "torque":
        return torque_figure(traces, 0, title)
    if kind == "paths":
        return paths_figure(traces, fixtures, title)
    if kind == "pitch":
        return pitch_figure(traces, title)
    raise ValueError(f"unknown plot kind {kind!r}; allowed: {', '.join(PLOT_KINDS)}")


def plot_traces(
    traces: Sequence[RunTrace],
    out_dir: Path,
    *,
    fixtures: Sequence[FixtureOutline] = (),
    kinds: Sequence[str] = PLOT_KINDS,
    prefix: str = "",
    titles: dict[str, str] | None = None,
    dpi: int = 100,
) -> tuple[PlotFile, ...]:
    """Write one PNG per kind to `out_dir/<prefix><FILE_NAMES[kind]>`; nothing when `traces`
    is empty (every run broke)."""
    if not traces:
        return ()
    series = [tr.label for tr in traces]
    out = []
    for kind in kinds:
        fig = build_figure(kind, traces, fixtures, (titles or {}).get(kind))
        out.append(save_figure(fig, out_dir / f"{prefix}{FILE_NAMES[kind]}", kind, series, dpi))
    return tuple(out)


def comparison_titles(scenario_name: str, labels: Sequence[str]) -> dict[str, str]:
    """Plot titles naming the scenario and the runs compared ("a vs b")."""
    vs = " vs ".join(labels)
    return {
        "yaw": f"{scenario_name}: trunk yaw, {vs}",
        "contacts": f"{scenario_name}: contact timeline, {vs}",
        "torque": f"{scenario_name}: left leg joint torques against their limits, {vs}",
        "paths": f"{scenario_name}: trunk and object paths, {vs}",
        "pitch": f"{scenario_name}: trunk lean, shift and height, {vs}",
    }


def plot_comparison(
    comparison: Comparison,
    out_dir: Path | None = None,
    *,
    prefix: str = "",
    dpi: int = 100,
) -> tuple[PlotFile, ...]:
    """Every plot of a comparison (both runs in each) in `out_dir` (default: the
    comparison's own directory). A run that broke has no trace and is left out; nothing is
    drawn when both broke."""
    traces = [o.trace for o in comparison.outcomes if o.trace is not None]
    return plot_traces(
        traces,
        comparison.out_dir if out_dir is None else out_dir,
        fixtures=comparison.fixtures,
        prefix=prefix,
        titles=comparison_titles(comparison.scenario_name, comparison.labels),
        dpi=dpi,
    )
