"""The static payload margins of a plan's carry and place poses, for `locoplan plan`."""

from __future__ import annotations

import math

from rich.table import Table

from locoplan.plan.payload import PayloadMargin


def payload_table(margins: tuple[PayloadMargin, ...]) -> Table:
    """One row per grasp pose (its reach margin and its lift's balance), carry or place pose
    (`locoplan.plan.payload.payload_margins`): the mass, reach margin, worst static torque
    ratio and its joint, centre-of-mass margin, the pelvis shift the analysis used and the
    payload limit of the pose. A carry or place pose out of the arms' reach says how far short
    of it the hands stop (at the nearest posture they reach; the object between them rides
    that much lower or nearer). (HECTOR, envelope seed 54021: carry poses 4.5-5.4 cm out of reach,
    boxes 0.11-0.12 m wide gripped 0.6-0.7 m high; the boxes rode 3.0-4.5 cm under their
    plan, against about 1 cm for reachable ones, and one such parcel came down on its
    platform's edge while the robot turned towards it.)"""
    table = Table(title="static payload margins", title_justify="left", show_header=False)
    table.add_column("pose")
    table.add_column("margins")
    for m in margins:
        a = m.analysis
        if m.hold.kind == "grasp":
            lift = ""
            if m.lift is not None:
                where = "inside" if m.lift.margin >= 0.0 else "past"
                lift = (
                    f"; lifting {m.lift_mass:g} kg with the trunk leaned back {m.lean:.3f} m: "
                    f"combined CoM {abs(m.lift.margin):.3f} m {where} the toes"
                )
            table.add_row(
                f"{m.hold.object} grasp (task {m.hold.task_index})",
                f"on its support: reach margin {a.reach_margin:+.3f} m{lift}",
            )
            continue
        ratio = f"{a.torque_ratio:.2f} ({a.joint})" if a.balanced else "unbalanced"
        limit = f"{a.payload_limit:.1f} kg" if math.isfinite(a.payload_limit) else "none"
        short = (
            f"; out of reach: the hands stop up to {-a.reach_margin:.3f} m short of this pose "
            "(the object rides lower or nearer)"
            if a.reach_margin < 0.0
            else ""
        )
        table.add_row(
            f"{m.hold.object} {m.hold.kind} (task {m.hold.task_index})",
            f"{m.hold.mass:g} kg: reach margin {a.reach_margin:+.3f} m, torque ratio {ratio}, "
            f"CoM margin {a.com_margin:+.3f} m, pelvis shift {a.shift:.3f} m, "
            f"payload limit {limit}{short}",
        )
    return table
