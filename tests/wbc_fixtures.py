"""Recorded whole-body-controller inputs for the WBC and task tests.

tests/data/wbc_ticks.npz holds 169 ticks of scenarios/walk-square.yaml (every 40th WBC tick
of the first 8 s plus every tick at a contact switch), recorded by benchmarks/wbc_tick.py
with the WBC as it was before the lean QP path (commit 0214223): the arguments of
`build_tasks`, M, h, the stance contacts, tau_ext, and the torques that WBC returned.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

import numpy as np

from locoplan.control.tasks import TaskGains
from locoplan.control.wbc import StanceContact

DATA = Path(__file__).parent / "data" / "wbc_ticks.npz"


@functools.cache
def recording() -> dict[str, np.ndarray]:
    """The recorded arrays, stacked over ticks (read-only)."""
    with np.load(DATA, allow_pickle=False) as f:
        rec = {k: f[k] for k in f.files}
    for a in rec.values():
        a.flags.writeable = False
    return rec


def n_ticks() -> int:
    return int(recording()["q"].shape[0])


def task_args(i: int) -> tuple[Any, ...]:
    """The `build_tasks` arguments of tick i."""
    rec = recording()
    gains = TaskGains(
        *(
            tuple(float(x) for x in rec[f"gain_{f}"])
            if rec[f"gain_{f}"].size > 1
            else float(rec[f"gain_{f}"][0])
            for f in TaskGains.__slots__
        )
    )
    swing = [
        (
            rec["swing_pva"][i, j, 0],
            rec["swing_pva"][i, j, 1],
            rec["swing_pva"][i, j, 2],
            float(rec["swing_yaw"][i, j]),
        )
        for j in range(int(rec["n_swing"][i]))
    ]
    return (
        gains,
        rec["q"][i],
        rec["v"][i],
        rec["R"][i],
        rec["omega"][i],
        rec["p_des"][i],
        rec["v_des"][i],
        float(rec["yaw_des"][i]),
        float(rec["yaw_rate_des"][i]),
        rec["J_base"][i],
        rec["dJv_base"][i],
        tuple(bool(s) for s in rec["stance"][i]),
        list(rec["J_feet"][i]),
        list(rec["dJv_feet"][i]),
        list(rec["v_feet"][i]),
        rec["p_feet"][i],
        list(rec["R_feet"][i]),
        swing,
        list(rec["J_hands"][i]),
        list(rec["dJv_hands"][i]),
        rec["hand_acc"][i],
    )


def contacts(i: int) -> list[StanceContact]:
    """The stance contacts the WBC got at tick i."""
    rec = recording()
    return [
        StanceContact(rec["J_feet"][i, k], float(rec["contact_yaw"][i, k]), rec["contact_w5"][i, k])
        for k in range(2)
        if rec["stance"][i, k]
    ]
