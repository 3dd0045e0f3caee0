"""Rich rendering of a run's metrics (the CLI prints it; nothing here prints)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from rich.table import Table


def _fmt(v: Any, unit: str = "") -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:.3g}{unit}" if abs(v) < 1e4 else f"{v:.0f}{unit}"
    return f"{v}{unit}"


def metrics_table(m: Mapping[str, Any]) -> Table:
    """One run's headline metrics and expectations as a two-column table."""
    t = Table(title=f"{m['scenario']} ({m['strategy']}, {m['model']})", show_header=False)
    t.add_column("metric", style="bold")
    t.add_column("value")
    mpc, wbc = m["mpc_solve_ms"], m["wbc_solve_ms"]
    rows = [
        ("completed", _fmt(m["completed"])),
        ("completion time", _fmt(m["completion_time"], " s")),
        ("fell", _fmt(m["fell"]) + (f" (t={m['fall_time']:.2f} s)" if m.get("fall_time") else "")),
        ("yaw difference pick->drop", _fmt(m["yaw_difference_deg"], " deg")),
        (
            "peak torque ratio",
            f"{m['peak_torque_ratio']:.2f} ({m.get('peak_torque_joint', '?')}); "
            f"commanded {m.get('peak_commanded_torque_ratio', 0.0):.2f}",
        ),
        ("torque clips (last guard)", _fmt(m.get("torque_clips", 0))),
        ("final base", f"{m['final_base']['position']}  yaw {m['final_base']['yaw_deg']} deg"),
        ("sim / wall time", f"{m['sim_time']:.2f} s / {m['wall_time']:.2f} s"),
        ("real-time factor", f"{m['real_time_factor']:.2f}x"),
        (
            "MPC update ms (median / p99)",
            f"{mpc['median']:.2f} / {mpc['p99']:.2f} (n={mpc['count']})",
        ),
        (
            "WBC tick ms (median / p99)",
            f"{wbc['median']:.3f} / {wbc['p99']:.3f} (n={wbc['count']})",
        ),
    ]
    for name, o in m.get("objects", {}).items():
        rows.append((f"object {name}", f"{o['position']} on={o['on']} held={_fmt(o['held'])}"))
    for name, e in m.get("expectations", {}).items():
        mark = "[green]ok[/green]" if e["ok"] else "[red]FAILED[/red]"
        rows.append(
            (f"expect {name}", f"{mark}  value={_fmt(e['value'])} limit={_fmt(e['limit'])}")
        )
    if m.get("log"):
        rows.append(("log", str(m["log"])))
    for k, v in rows:
        t.add_row(k, v)
    return t
