"""Nominal footholds: where each foot stands, or will touch down, along the trunk reference.

A foot starts under the initial trunk pose, `foot_width / 2` to its side. A swing's foothold is
that lateral offset from the trunk reference at the middle of the stance that follows it
(touchdown + (period - swing) / 2, the instant the trunk passes over it), except that the last
swing of each foot in a locomotion task lands beside the task's final pose, so the robot ends
every walk or turn square. These are nominal: the controller adds its own feedback (Raibert
term) on top.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from locoplan.plan.gait import ContactSchedule, side_index
from locoplan.plan.trunk import TrunkPath

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True, eq=False)
class Footholds:
    """Per foot f: `positions[f]` (k_f + 1, 3) world m (z = 0) and `yaws[f]` (k_f + 1,) rad;
    row 0 is the initial stance, row i the foothold of the foot's i-th swing (from its
    lift-off on)."""

    positions: tuple[FloatArray, FloatArray]
    yaws: tuple[FloatArray, FloatArray]
    _liftoffs: tuple[FloatArray, FloatArray]

    def at(self, times: npt.ArrayLike) -> FloatArray:
        """Footholds (n, 2, 3) at `times` (n,): the stance position, or during a swing its
        touchdown target."""
        times = np.asarray(times, dtype=float)
        out = np.empty((times.shape[0], 2, 3))
        for f in (0, 1):
            i = np.searchsorted(self._liftoffs[f], times, side="right")
            out[:, f, :] = self.positions[f][i]
        return out

    def foothold_at(self, foot: int | str, t: float) -> FloatArray:
        """Foothold (3,) of one foot at time t (see `at`)."""
        f = side_index(foot)
        i = int(np.searchsorted(self._liftoffs[f], t, side="right"))
        return self.positions[f][i].copy()


def build_footholds(contacts: ContactSchedule, trunk: TrunkPath, foot_width: float) -> Footholds:
    """Nominal footholds for every swing of the contact schedule."""
    positions: list[FloatArray] = []
    yaws: list[FloatArray] = []
    block_of = {b.task_index: b for b in contacts.blocks}
    for f, side in ((0, 1.0), (1, -1.0)):
        starts = contacts.swing_start[f]
        ends = contacts.swing_end[f]
        owners = contacts.swing_task[f]
        times = [-math.inf]
        for j in range(starts.size):
            block = block_of[owners[j]]
            last_in_block = j + 1 >= starts.size or owners[j + 1] != owners[j]
            if last_in_block:
                times.append(block.end)
            else:
                mid = float(ends[j]) + (block.period - block.swing) / 2.0
                times.append(min(mid, block.end))
        rows = np.empty((len(times), 3))
        yaw_row = np.empty(len(times))
        for r, t in enumerate(times):
            x, y, yaw, *_ = trunk.pose_at(t)
            rows[r] = (
                x - math.sin(yaw) * side * foot_width / 2.0,
                y + math.cos(yaw) * side * foot_width / 2.0,
                0.0,
            )
            yaw_row[r] = yaw
        positions.append(rows)
        yaws.append(yaw_row)
    return Footholds(
        positions=(positions[0], positions[1]),
        yaws=(yaws[0], yaws[1]),
        _liftoffs=(contacts.swing_start[0], contacts.swing_start[1]),
    )
