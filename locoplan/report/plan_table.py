"""Rich tables of a compiled plan (`locoplan plan`). Returns renderables; only the CLI prints."""

from __future__ import annotations

import math
from itertools import groupby

from rich.console import Group, RenderableType
from rich.table import Table

from locoplan.plan import Plan, PlannedTask


def _s(t: float) -> str:
    return "end" if math.isinf(t) else f"{t:.3f}"


def _span(a: float, b: float) -> str:
    return f"{_s(a)}–{_s(b)}"


def _task_detail(task: PlannedTask) -> str:
    if task.action == "turn" and task.angle is not None:
        return f"{math.degrees(task.angle):+.1f}°"
    if task.action == "walk" and task.distance is not None:
        return f"[{task.distance[0]:g}, {task.distance[1]:g}] m (body frame)"
    parts: list[str] = []
    if task.object is not None:
        parts.append(task.object)
    if task.hands is not None and task.hands != "both":
        parts.append(f"{task.hands} hand")
    if task.onto is not None:
        parts.append(f"onto {task.onto}")
    if task.at is not None:
        parts.append("at [" + ", ".join(f"{v:g}" for v in task.at) + "]")
    if task.velocity is not None:
        parts.append("v [" + ", ".join(f"{v:g}" for v in task.velocity) + "] m/s")
    return ", ".join(parts)


def tasks_table(plan: Plan) -> Table:
    """One row per task: index in the file, action, planned start/end, shift, details."""
    table = Table(title=f"{plan.scenario_name} — {plan.strategy} plan", title_justify="left")
    table.add_column("#", justify="right")
    table.add_column("action")
    table.add_column("start s", justify="right")
    table.add_column("end s", justify="right")
    table.add_column("shift s", justify="right")
    table.add_column("details")
    for task in plan.tasks:
        shift = f"{task.shift:+.3f}" if task.shift else ""
        table.add_row(
            str(task.index),
            task.action,
            _s(task.start),
            _s(task.end),
            shift,
            _task_detail(task),
        )
    return table


def schedule_table(plan: Plan) -> Table:
    """Per foot and hand the phases, and the object-held intervals."""
    table = Table(title="contact schedule", title_justify="left")
    table.add_column("limb")
    table.add_column("phase")
    table.add_column("time s")
    table.add_column("note")
    blocks = {b.task_index: b for b in plan.contacts.blocks}
    for f, name in enumerate(("L", "R")):
        limb = f"{name} foot"
        starts = plan.contacts.swing_start[f].tolist()
        ends = plan.contacts.swing_end[f].tolist()
        owners = plan.contacts.swing_task[f]
        stance = plan.stance_intervals(name)
        table.add_row(limb, "stance", f"{len(stance)} intervals", "both feet outside locomotion")
        rows = list(zip(starts, ends, owners, strict=True))
        for owner, group in groupby(rows, key=lambda r: r[2]):
            swings = list(group)
            b = blocks[owner]
            note = (
                f"task {owner}: {b.cycles} cycle{'s' if b.cycles != 1 else ''} of "
                f"{b.period:.3f} s, swing {b.swing:.3f} s"
            )
            table.add_row("", f"swing ×{len(swings)}", _span(swings[0][0], swings[-1][1]), note)
        if not rows:
            table.add_row("", "stance", _span(0.0, plan.t_end), "no stepping")
    for h, name in enumerate(("L", "R")):
        limb = f"{name} hand"
        track = plan.manipulation.tracks[h]
        first = True
        previous_end: float | None = None
        for g in track.segments:
            if previous_end is not None and g.t0 > previous_end:
                table.add_row("", "hold", _span(previous_end, g.t0), "last pose")
            note = f"task {g.task_index}: {g.start.frame} → {g.end.frame}"
            table.add_row(limb if first else "", g.label, _span(g.t0, g.t1), note)
            previous_end = g.t1
            first = False
        for c in plan.manipulation.contacts[h]:
            table.add_row(limb if first else "", "contact", _span(c.t0, c.t1), c.object)
            first = False
        if first:
            table.add_row(limb, "default", _span(0.0, plan.t_end), "carry-ready pose")
    for hold in plan.holds:
        note = f"{hold.mass:g} kg, hands {'+'.join(hold.hands)}"
        if hold.release_kind is not None:
            note += f", {hold.release_kind} (task {hold.release_task})"
        table.add_row(f"object {hold.object}", "held", _span(hold.lift, hold.release), note)
    return table


def summary_table(plan: Plan) -> Table:
    """Reference summary: final pose, total time, re-timing shift, object targets."""
    x, y, yaw = plan.final_pose
    table = Table(title="reference", title_justify="left", show_header=False)
    table.add_column("quantity")
    table.add_column("value")
    table.add_row("final position", f"[{x:.3f}, {y:.3f}, {plan.base_height:.3f}] m")
    table.add_row("final yaw", f"{math.degrees(yaw):.1f}°")
    table.add_row("total time", f"{plan.t_end:.3f} s")
    if plan.end_shift:
        table.add_row("re-timing", f"+{plan.end_shift:.3f} s (quasi-static)")
    for name, tgt in plan.manipulation.targets.items():
        if tgt.position is None:
            value = f"{tgt.kind}"
        else:
            where = f" on {tgt.fixture}" if tgt.fixture else ""
            p = ", ".join(f"{v:.3f}" for v in tgt.position)
            value = f"{tgt.kind}{where} [{p}] m"
        table.add_row(f"object {name}", value)
    return table


def plan_table(plan: Plan) -> RenderableType:
    """Everything `locoplan plan` prints: tasks, contact schedule and reference summary."""
    return Group(tasks_table(plan), schedule_table(plan), summary_table(plan))
