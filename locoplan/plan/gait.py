"""Foot contact schedule: stance/swing per foot from the locomotion tasks (sigma_C1, sigma_C2).

During every locomotion task (step, walk, turn) the feet alternate with the scenario's gait:
n = max(1, round(duration / period)) whole cycles fit the task exactly (period' = duration / n),
the swing time is kept but capped at period' / 2 - GAIT_MIN_DOUBLE_SUPPORT. A task that starts
the simulation first shifts the weight (`start_lead`): its n cycles fit what is left. In each cycle
starting at c the LEFT foot swings on [c, c + swing), the RIGHT foot on
[c + period'/2, c + period'/2 + swing). Outside locomotion both feet stand. Swing intervals are
half-open: at the touchdown instant the foot is in stance again.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from locoplan.plan.constants import GAIT_MIN_DOUBLE_SUPPORT
from locoplan.plan.errors import PlanError
from locoplan.plan.tasks import PlannedTask

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

FOOT_NAMES: tuple[str, str] = ("L", "R")


def side_index(side: int | str) -> int:
    """0 for the left foot/hand ("L", "left", 0), 1 for the right ("R", "right", 1)."""
    if side in (0, "L", "l", "left"):
        return 0
    if side in (1, "R", "r", "right"):
        return 1
    raise ValueError(f"unknown side {side!r}: use 'L'/'R' (or 0/1)")


@dataclass(frozen=True, slots=True)
class SwingPhase:
    """A foot's current swing: lift-off and touchdown times (s) and `phase` in [0, 1]."""

    liftoff: float
    touchdown: float
    phase: float

    @property
    def duration(self) -> float:
        """Swing duration (s)."""
        return self.touchdown - self.liftoff


@dataclass(frozen=True, slots=True)
class GaitBlock:
    """The gait used in one locomotion task: `cycles` cycles of `period` s with `swing` s swings."""

    task_index: int
    start: float
    end: float
    cycles: int
    period: float
    swing: float


@dataclass(frozen=True, slots=True, eq=False)
class ContactSchedule:
    """Swing intervals per foot (sorted, non-overlapping) and their evaluation.

    `swing_start[f]`, `swing_end[f]`: arrays (k_f,) of lift-off and touchdown times (s) of foot f
    (0 = left, 1 = right); `swing_task[f]`: the locomotion task index of each swing.
    """

    blocks: tuple[GaitBlock, ...]
    swing_start: tuple[FloatArray, FloatArray]
    swing_end: tuple[FloatArray, FloatArray]
    swing_task: tuple[tuple[int, ...], tuple[int, ...]]
    _starts_list: tuple[list[float], list[float]]

    def swing_intervals(self, foot: int | str) -> tuple[tuple[float, float], ...]:
        """Swing intervals [lift-off, touchdown) of the foot, sorted (s)."""
        f = side_index(foot)
        return tuple(zip(self.swing_start[f].tolist(), self.swing_end[f].tolist(), strict=True))

    def stance_intervals(self, foot: int | str, t_end: float) -> tuple[tuple[float, float], ...]:
        """Stance intervals of the foot over [0, t_end], the complement of its swings (s)."""
        out: list[tuple[float, float]] = []
        t = 0.0
        for a, b in self.swing_intervals(foot):
            if a > t:
                out.append((t, a))
            t = b
        if t < t_end:
            out.append((t, t_end))
        return tuple(out)

    def _swing_index(self, f: int, t: float) -> int:
        """Index of the swing of foot f containing t, or -1."""
        i = bisect.bisect_right(self._starts_list[f], t) - 1
        if i >= 0 and t < self.swing_end[f][i]:
            return i
        return -1

    def in_stance(self, foot: int | str, t: float | npt.ArrayLike) -> bool | BoolArray:
        """Whether the foot is in stance at time t (scalar) or at each time of an array."""
        f = side_index(foot)
        if isinstance(t, float | int):
            return self._swing_index(f, float(t)) < 0
        times = np.asarray(t, dtype=float)
        if times.ndim == 0:
            return self._swing_index(f, float(times)) < 0
        return ~self._swinging(f, times)

    def _swinging(self, f: int, times: FloatArray) -> BoolArray:
        starts = self.swing_start[f]
        if starts.size == 0:
            return np.zeros(times.shape, dtype=bool)
        i = np.searchsorted(starts, times, side="right") - 1
        ok = i >= 0
        return ok & (times < self.swing_end[f][np.maximum(i, 0)])

    def flags(self, times: npt.ArrayLike) -> BoolArray:
        """Stance flags (n, 2) bool: column 0 left foot, column 1 right (sigma_C1, sigma_C2)."""
        times = np.asarray(times, dtype=float)
        out = np.empty((times.shape[0], 2), dtype=bool)
        out[:, 0] = ~self._swinging(0, times)
        out[:, 1] = ~self._swinging(1, times)
        return out

    def swing_phase(self, foot: int | str, t: float) -> SwingPhase | None:
        """The foot's swing at time t, or None when it is in stance."""
        f = side_index(foot)
        i = self._swing_index(f, t)
        if i < 0:
            return None
        a = float(self.swing_start[f][i])
        b = float(self.swing_end[f][i])
        return SwingPhase(a, b, (t - a) / (b - a))

    def next_touchdown(self, foot: int | str, t: float) -> float | None:
        """Touchdown time of the swing in progress at t, else of the next swing, else None."""
        f = side_index(foot)
        i = self._swing_index(f, t)
        if i >= 0:
            return float(self.swing_end[f][i])
        j = bisect.bisect_right(self._starts_list[f], t)
        if j < len(self._starts_list[f]):
            return float(self.swing_end[f][j])
        return None

    def stance_start(self, foot: int | str, t: float) -> float | None:
        """Touchdown time starting the stance that contains t; during a swing, that swing's
        touchdown; None when no touchdown happened before t (the initial stance)."""
        f = side_index(foot)
        i = bisect.bisect_right(self._starts_list[f], t) - 1
        if i < 0:
            return None
        return float(self.swing_end[f][i])

    def stance_starts(self, foot: int | str, times: npt.ArrayLike) -> FloatArray:
        """`stance_start` at each time (n,): touchdown times (s), NaN for the initial stance."""
        f = side_index(foot)
        t = np.asarray(times, dtype=float)
        ends = self.swing_end[f]
        if ends.size == 0:
            return np.full(t.shape, np.nan)
        i = np.searchsorted(self.swing_start[f], t, side="right") - 1
        return np.where(i >= 0, ends[np.maximum(i, 0)], np.nan)

    def block_at(self, t: float) -> GaitBlock | None:
        """The gait block (locomotion task) whose [start, end) contains t, or None."""
        for block in self.blocks:
            if block.start <= t < block.end:
                return block
        return None

    def next_liftoff(self, foot: int | str, t: float) -> float | None:
        """First lift-off time strictly after t, or None."""
        f = side_index(foot)
        j = bisect.bisect_right(self._starts_list[f], t)
        if j < len(self._starts_list[f]):
            return self._starts_list[f][j]
        return None


def gait_cycles(task: PlannedTask, period: float) -> int:
    """How many whole gait cycles a locomotion task holds: max(1, round(duration / period))."""
    return max(1, round((task.end - task.start) / period))


def start_lead(task: PlannedTask, period: float, settle: float) -> float:
    """How long (s) a locomotion task starting before `settle` s waits before its first
    lift-off: until `settle`, but at most half a gait `period` (the time the other foot waits
    anyway) and at most what leaves every cycle the task would have had half a period
    (`gait_block` fits the same number of cycles into what is left).

    Why: the MPC shifts the weight onto the stance foot before a lift-off that it sees
    coming in its horizon. At the simulation's start it sees none: a task starting at 0 s
    lifted the left foot with the CoM centred between the feet, the CoM fell towards the
    swing side for the whole single support, and with swings of half the period (no double
    support left to bring it back) the robot walked off sideways: stepping in place with a
    0.5 s period and 0.25 s swings drifted 9.9 cm in 2.6 s, a -110 deg turn 17 cm (standing
    1 s first: 0.3 and 2.8 cm; with the lead: 0.2 and 2.2 cm). `settle` is the robot's
    pendulum time sqrt(z / g) (`PlanGeometry.settle_time`), the time the centre of pressure
    held at one foot takes to move the CoM by a sizeable share of the half stance width.
    The number of cycles is kept because the hip yaw bounds a turn per stance: refitting
    whole cycles into what was left turned an H1 transfer's -54 deg in 0.85 s in one cycle
    instead of two, and it fell (seed 57027, transfer-008)."""
    if task.start >= settle:
        return 0.0
    duration = task.end - task.start
    cycles = gait_cycles(task, period)
    return max(0.0, min(settle - task.start, period / 2.0, duration - cycles * period / 2.0))


def gait_block(task: PlannedTask, period: float, swing: float, lead: float = 0.0) -> GaitBlock:
    """Fit whole gait cycles into a locomotion task (see the module docstring); with a `lead`
    (`start_lead`), the same number of cycles into the task after it."""
    n = gait_cycles(task, period)
    p = (task.end - task.start - lead) / n
    s = min(swing, p / 2.0 - GAIT_MIN_DOUBLE_SUPPORT)
    if s <= 0.0:
        raise PlanError(
            f"{task.action} lasts {task.end - task.start:g} s: too short for one gait cycle "
            f"with {GAIT_MIN_DOUBLE_SUPPORT:g} s of double support after each swing",
            task.index,
        )
    return GaitBlock(task.index, task.start + lead, task.end, n, p, s)


def build_contact_schedule(
    tasks: tuple[PlannedTask, ...], period: float, swing: float, settle: float = 0.0
) -> ContactSchedule:
    """Contact schedule of the feet for the (sorted) planned tasks; no foot lifts off before
    `settle` s (`start_lead`)."""
    blocks: list[GaitBlock] = []
    starts: tuple[list[float], list[float]] = ([], [])
    ends: tuple[list[float], list[float]] = ([], [])
    owners: tuple[list[int], list[int]] = ([], [])
    last_end = -np.inf
    last_index = -1
    for task in tasks:
        if task.kind != "locomotion":
            continue
        if task.start < last_end - 1e-9:
            raise PlanError(
                f"{task.action} at {task.start:g} s overlaps the locomotion task {last_index} "
                f"(until {last_end:g} s): two locomotion tasks cannot run at once",
                task.index,
            )
        block = gait_block(task, period, swing, start_lead(task, period, settle))
        blocks.append(block)
        for k in range(block.cycles):
            c = block.start + k * block.period
            for f, offset in ((0, 0.0), (1, block.period / 2.0)):
                starts[f].append(c + offset)
                ends[f].append(c + offset + block.swing)
                owners[f].append(task.index)
        last_end = task.end
        last_index = task.index
    return ContactSchedule(
        blocks=tuple(blocks),
        swing_start=(np.asarray(starts[0], dtype=float), np.asarray(starts[1], dtype=float)),
        swing_end=(np.asarray(ends[0], dtype=float), np.asarray(ends[1], dtype=float)),
        swing_task=(tuple(owners[0]), tuple(owners[1])),
        _starts_list=(list(starts[0]), list(starts[1])),
    )
