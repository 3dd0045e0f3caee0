"""The static payload margins of a plan's carry and place poses, for `locoplan plan`."""

from __future__ import annotations

import math

from rich.table import Table

from locoplan.plan.payload import PayloadMargin


def payload_table(margins: tuple[PayloadMargin, ...]) -> Table:
    """One row per grasp pose (its reach margin only), carry or place pose
    (`locoplan.plan.payload.payload_margins`): the mass, reach margin, worst static torque
    ratio and its joint, centre-of-mass margin, the pelvis shift the analysis used and the
    payload limit of the pose."""
    table = Table(title="static payload margins", title_justify="left", show_header=False)
    table.add_column("pose")
    table.add_column("margins")
    for m in margins:
        a = m.analysis
        if m.hold.kind == "grasp":
            table.add_row(
                f"{m.hold.object} grasp (task {m.hold.task_index})",
                f"on its support: reach margin {a.reach_margin:+.3f} m",
            )
            continue
        ratio = f"{a.torque_ratio:.2f} ({a.joint})" if a.balanced else "unbalanced"
        limit = f"{a.payload_limit:.1f} kg" if math.isfinite(a.payload_limit) else "none"
        table.add_row(
            f"{m.hold.object} {m.hold.kind} (task {m.hold.task_index})",
            f"{m.hold.mass:g} kg: reach margin {a.reach_margin:+.3f} m, torque ratio {ratio}, "
            f"CoM margin {a.com_margin:+.3f} m, pelvis shift {a.shift:.3f} m, "
            f"payload limit {limit}",
        )
    return table
