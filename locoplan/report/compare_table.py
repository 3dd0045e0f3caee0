"""Rich side-by-side table of a comparison (the CLI prints it; nothing here prints).

Columns: metric, the two runs in compare.json order, and the difference proposed - baseline
(dynamic - quasi-static, or external-force - combined: the paper's claim is about that sign).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rich.table import Table

from locoplan.compare.comparison import Comparison
from locoplan.compare.variants import baseline_and_proposed


def _num(v: Any, fmt: str, unit: str = "") -> str:
    if v is None:
        return "-"
    return f"{v:{fmt}}{unit}"


def _yes_no(v: Any) -> str:
    if v is None:
        return "-"
    return "yes" if v else "no"


def object_whereabouts(o: Mapping[str, Any]) -> str:
    """Where a metrics `objects` entry ended: "in the hands", "on <fixture>" or "on no
    fixture" (the grasp wins: a held object hovering over its table is not on it)."""
    if o.get("held"):
        return "in the hands"
    return f"on {o.get('on')}" if o.get("on") else "on no fixture"


def _placed(m: Mapping[str, Any]) -> str:
    """Where each object ended: "package on conveyor", or "none" without objects."""
    objects = m.get("objects") or {}
    if not objects:
        return "no objects"
    parts = []
    for name, o in objects.items():
        parts.append(f"{name} {object_whereabouts(o)}")
    return ", ".join(parts)


def _placed_ok(m: Mapping[str, Any]) -> bool | None:
    results = [e["ok"] for k, e in (m.get("expectations") or {}).items() if k.startswith("placed.")]
    return None if not results else all(results)


def _fell(m: Mapping[str, Any]) -> str:
    if not m:
        return "-"
    when = m.get("fall_time")
    return _yes_no(m.get("fell")) + (f" (t={when:.2f} s)" if when is not None else "")


def _diff(v: float | None, fmt: str, unit: str = "") -> str:
    if v is None:
        return "-"
    return f"{v:+{fmt}}{unit}"


def compare_table(comparison: Comparison) -> Table:
    """The comparison as a table: completed, completion time, yaw difference, peak torque
    ratio and the joint that hit it, fell, placed, MPC update p99, real-time factor and the
    expectations (a run that broke shows its error there). Log paths are not in the table
    (they are in compare.json)."""
    base_label, prop_label = baseline_and_proposed(comparison.kind)
    labels = comparison.labels
    title = f"{comparison.scenario_name}: {' vs '.join(labels)}"
    t = Table(title=title, caption=f"Δ = {prop_label} − {base_label}")
    t.add_column("metric", style="bold")
    for label in labels:
        t.add_column(label, justify="right")
    t.add_column("Δ", justify="right")
    ms = [o.metrics or {} for o in comparison.outcomes]
    d = comparison.differences()

    def row(name: str, cells: list[str], diff: str = "") -> None:
        t.add_row(name, *cells, diff)

    row(
        "completed",
        [_yes_no(m.get("completed")) if m else "-" for m in ms],
    )
    row(
        "completion time",
        [_num(m.get("completion_time"), ".3f", " s") for m in ms],
        _diff(d["completion_time"], ".3f", " s"),
    )
    row(
        "yaw difference pick→drop",
        [_num(m.get("yaw_difference_deg"), ".1f", "°") for m in ms],
        _diff(d["yaw_difference_deg"], ".1f", "°"),
    )
    row(
        "peak torque ratio (joint)",
        [
            f"{m['peak_torque_ratio']:.2f} ({m.get('peak_torque_joint', '?')})"
            if m.get("peak_torque_ratio") is not None
            else "-"
            for m in ms
        ],
        _diff(d["peak_torque_ratio"], ".2f"),
    )
    row(
        "fell",
        [_fell(m) for m in ms],
    )
    row(
        "placed",
        [
            _placed(m)
            + ("" if (ok := _placed_ok(m)) is None else (" [green]ok[/]" if ok else " [red]✗[/]"))
            if m
            else "-"
            for m in ms
        ],
    )
    row(
        "MPC update p99",
        [_num((m.get("mpc_solve_ms") or {}).get("p99"), ".2f", " ms") for m in ms],
        _diff(d["mpc_solve_p99_ms"], ".2f", " ms"),
    )
    row(
        "real-time factor",
        [_num(m.get("real_time_factor"), ".2f", "x") for m in ms],
        _diff(d["real_time_factor"], ".2f", "x"),
    )
    row(
        "expectations",
        [_expectations(o.metrics, o.error) for o in comparison.outcomes],
    )
    return t


def _expectations(m: Mapping[str, Any] | None, error: str | None) -> str:
    if error is not None:
        return f"[red]run broke:[/] {error}"
    if m is None:
        return "-"
    failed = [k for k, e in (m.get("expectations") or {}).items() if not e["ok"]]
    if not failed:
        return "[green]all held[/]"
    return "[red]failed:[/] " + ", ".join(failed)
