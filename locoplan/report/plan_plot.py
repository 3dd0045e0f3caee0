"""Timeline plot of a compiled plan (`locoplan plan --plot`), drawn with matplotlib's Agg
canvas directly (no pyplot, no global backend switch)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from locoplan.plan import Plan

_STANCE = "#b5dcc0"
_SWING = "#f28e2b"
_HAND_ACTIVE = "#a0cbe8"
_HAND_CONTACT = "#1f77b4"
_HELD = "#9467bd"
_LOCO = "#59a14f"
_MANIP = "#e15759"
_STAND = "#bab0ac"


def _bars(a_b: list[tuple[float, float]], t_end: float) -> list[tuple[float, float]]:
    return [(a, min(b, t_end) - a) for a, b in a_b if min(b, t_end) > a]


def plot_plan(plan: Plan, path: str | Path, *, dpi: int = 120) -> Path:
    """Draw the plan's timeline and yaw reference to a PNG at `path`; returns the path.

    Top panel rows (top to bottom): one per task, then L foot, R foot (stance / swing),
    L hand, R hand (active / in contact), object held. Bottom panel: planned trunk yaw (deg)
    with the grasp, lift and release instants.
    """
    t_end = plan.t_end
    rows: list[str] = []
    fig = Figure(figsize=(11.0, 6.0 + 0.25 * len(plan.tasks)), layout="constrained")
    FigureCanvasAgg(fig)
    ax, ax_yaw = fig.subplots(2, 1, sharex=True, height_ratios=(3.0, 1.4))

    def row(label: str) -> float:
        rows.append(label)
        return float(-len(rows))

    h = 0.7
    for task in plan.tasks:
        y = row(f"#{task.index} {task.action}")
        color = {"locomotion": _LOCO, "manipulation": _MANIP}.get(task.kind, _STAND)
        ax.broken_barh([(task.start, task.end - task.start)], (y - h / 2, h), color=color)
    for f in ("L", "R"):
        y = row(f"{f} foot")
        ax.broken_barh(_bars(list(plan.stance_intervals(f)), t_end), (y - h / 2, h), color=_STANCE)
        ax.broken_barh(_bars(list(plan.swing_intervals(f)), t_end), (y - h / 2, h), color=_SWING)
    for i, hand in enumerate(("L", "R")):
        y = row(f"{hand} hand")
        active = plan.manipulation.active_intervals[i].as_tuples()
        contact = plan.manipulation.contact_intervals[i].as_tuples()
        ax.broken_barh(_bars(list(active), t_end), (y - h / 2, h), color=_HAND_ACTIVE)
        ax.broken_barh(_bars(list(contact), t_end), (y - h / 2, h), color=_HAND_CONTACT)
    y = row("object held")
    for hold in plan.holds:
        ax.broken_barh(_bars([(hold.lift, hold.release)], t_end), (y - h / 2, h), color=_HELD)
        ax.text(hold.lift + 0.02, y, f"{hold.object} {hold.mass:g} kg", va="center", fontsize=8)
    ax.set_yticks([-(i + 1) for i in range(len(rows))], rows)
    ax.set_ylim(-len(rows) - 0.6, -0.4)
    ax.set_xlim(0.0, t_end)
    ax.grid(axis="x", alpha=0.3)
    ax.set_title(f"{plan.scenario_name} — {plan.strategy} plan ({t_end:.2f} s)")
    ax.legend(
        handles=[
            Patch(color=_LOCO, label="locomotion"),
            Patch(color=_MANIP, label="manipulation"),
            Patch(color=_STANCE, label="stance"),
            Patch(color=_SWING, label="swing"),
            Patch(color=_HAND_ACTIVE, label="hand active"),
            Patch(color=_HAND_CONTACT, label="hand contact"),
            Patch(color=_HELD, label="object held"),
        ],
        loc="upper left",
        bbox_to_anchor=(1.0, 1.0),
        fontsize=8,
    )

    times = np.linspace(0.0, t_end, max(200, math.ceil(t_end * 100) + 1))
    ref = plan.trunk_reference(times)
    yaw_deg = np.degrees(ref.yaw)
    ax_yaw.plot(times, yaw_deg, color="black", lw=1.5, label="yaw reference")
    # at least +-10 deg of range, so that a constant yaw reads as constant
    mid = 0.5 * (float(yaw_deg.max()) + float(yaw_deg.min()))
    half = max(10.0, 0.55 * (float(yaw_deg.max()) - float(yaw_deg.min())))
    ax_yaw.set_ylim(mid - half, mid + half)
    marks = {"grasp": ("tab:blue", ":"), "lift": ("tab:purple", "--"), "release": ("tab:red", "-.")}
    for event in plan.events:
        if event.kind in marks:
            color, style = marks[event.kind]
            ax_yaw.axvline(event.t, color=color, ls=style, lw=1.0)
            ax.axvline(event.t, color=color, ls=style, lw=0.8, alpha=0.6)
    # The paper's yaw-difference measure: trunk yaw at the start of a pick and of the drop or
    # throw of the same object.
    starts = {t.index: t.start for t in plan.tasks}
    for hold in plan.holds:
        if hold.release_task is None:
            continue
        t_pick, t_drop = starts[hold.pick_task], starts[hold.release_task]
        yaw_pick = math.degrees(plan.trunk_reference_at(t_pick).yaw)
        yaw_drop = math.degrees(plan.trunk_reference_at(t_drop).yaw)
        ax_yaw.plot([t_pick, t_drop], [yaw_pick, yaw_drop], "o", color="tab:red", ms=5)
        ax_yaw.annotate(
            f"Δyaw pick→{hold.release_kind} start {abs(yaw_drop - yaw_pick):.1f}°",
            (t_drop, yaw_drop),
            textcoords="offset points",
            xytext=(8, 8),
            fontsize=8,
        )
    ax_yaw.set_xlabel("time (s)")
    ax_yaw.set_ylabel("yaw (deg)")
    ax_yaw.grid(alpha=0.3)
    ax_yaw.legend(
        handles=[
            Patch(color="black", label="yaw reference"),
            *[Patch(color=c, label=k) for k, (c, _) in marks.items()],
        ],
        loc="upper left",
        bbox_to_anchor=(1.0, 1.0),
        fontsize=8,
    )
    out = Path(path)
    fig.savefig(out, dpi=dpi)
    return out
