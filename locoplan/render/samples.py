"""What one video frame needs, and which recorded samples become frames.

A `RenderSample` is the state of the whole MuJoCo scene at one instant: the full ``qpos`` of
the compiled scene (robot free joint, robot joints, then each object's free joint, in MuJoCo's
order), the planned stance flags and the label of the active tasks. The closed loop hands the
same values to the live video recorder and writes them to the log's ``/sim/qpos`` topic
(JSON; bit for bit with the writer's default encoding, rounded to the writer's
`json_decimals` otherwise: 6 places in `locoplan run`, a micrometre or a microradian, which
no frame shows); `locoplan render` decodes them again. Both paths then go through
`FrameClock`, so `run --video` and `render` turn the same samples into the same frames.

Times are compared as integer nanoseconds (as the log stores them), never as floats.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from locoplan.plan import Plan, PlannedTask

FloatArray = npt.NDArray[np.float64]

SAMPLE_TOPIC = "/sim/qpos"
NS_PER_S = 1_000_000_000
IDLE_LABEL = "idle"


def to_ns(t: float) -> int:
    """`t` (s) as integer nanoseconds, rounded as `RunLogWriter` rounds log times."""
    return round(t * 1e9)


@dataclass(frozen=True, slots=True)
class RenderSample:
    """The scene at time `t` (s): `qpos` (nq,) of the compiled MuJoCo scene, the planned
    stance flags (left, right) and `task`, the label of the tasks active at `t`."""

    t: float
    qpos: FloatArray
    stance: tuple[bool, bool]
    task: str

    @property
    def t_ns(self) -> int:
        """`t` in integer nanoseconds."""
        return to_ns(self.t)

    def to_payload(self) -> dict[str, Any]:
        """The JSON payload of ``/sim/qpos`` (time is the message's log time)."""
        return {"qpos": self.qpos, "stance": list(self.stance), "task": self.task}

    @staticmethod
    def from_payload(t: float, payload: Mapping[str, Any]) -> RenderSample:
        """Inverse of `to_payload`; ValueError for a payload without a finite qpos."""
        try:
            qpos = np.asarray(payload["qpos"], dtype=float)
            stance_raw = payload.get("stance") or (False, False)
            stance = (bool(stance_raw[0]), bool(stance_raw[1]))
            task = str(payload.get("task", ""))
        except (KeyError, TypeError, IndexError) as exc:
            raise ValueError(f"not a {SAMPLE_TOPIC} payload: {exc}") from exc
        if qpos.ndim != 1 or not np.all(np.isfinite(qpos)):
            raise ValueError(f"{SAMPLE_TOPIC} payload at t={t:.3f} s has no finite qpos vector")
        return RenderSample(t, qpos, stance, task)


def task_label(task: PlannedTask) -> str:
    """Short human label of one task: ``pick box``, ``turn -90 deg``, ``walk 0.60, 0.00 m``."""
    if task.action == "turn" and task.angle is not None:
        return f"turn {math.degrees(task.angle):+.0f} deg"
    if task.action == "walk" and task.distance is not None:
        return f"walk {task.distance[0]:.2f}, {task.distance[1]:.2f} m"
    if task.action == "drop" and task.object is not None and task.onto is not None:
        return f"drop {task.object} onto {task.onto}"
    if task.object is not None:
        return f"{task.action} {task.object}"
    return task.action


@dataclass(frozen=True, slots=True)
class TaskTimeline:
    """Planned task intervals [start, end) (s) and their labels, for `label_at`."""

    starts: tuple[float, ...]
    ends: tuple[float, ...]
    labels: tuple[str, ...]
    # Every start and end, sorted, and the label of each interval between two of them (the
    # active tasks change only there), so `label_at` is a bisection, not a scan of all tasks.
    _bounds: tuple[float, ...] = field(init=False, repr=False, compare=False)
    _segment_labels: tuple[str, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        bounds = tuple(sorted(set(self.starts) | set(self.ends)))
        object.__setattr__(self, "_bounds", bounds)
        object.__setattr__(self, "_segment_labels", tuple(map(self._scan, bounds)))

    @staticmethod
    def from_plan(plan: Plan) -> TaskTimeline:
        """The timeline of a compiled plan (re-timed tasks as planned)."""
        return TaskTimeline(
            tuple(task.start for task in plan.tasks),
            tuple(task.end for task in plan.tasks),
            tuple(task_label(task) for task in plan.tasks),
        )

    def label_at(self, t: float) -> str:
        """Labels of the tasks active at `t` joined by `` + ``, or ``idle``."""
        k = bisect.bisect_right(self._bounds, t) - 1
        # Before the first bound no task is active; within [bounds[k], bounds[k + 1]) the
        # active tasks are those active at bounds[k].
        return IDLE_LABEL if k < 0 else self._segment_labels[k]

    def _scan(self, t: float) -> str:
        active = [
            label
            for start, end, label in zip(self.starts, self.ends, self.labels, strict=True)
            if start <= t < end
        ]
        return " + ".join(active) if active else IDLE_LABEL


def frame_time_ns(index: int, fps: int) -> int:
    """Time (ns) of frame `index` at `fps` frames per second (frame 0 at t = 0)."""
    return index * NS_PER_S // fps


class FrameClock:
    """Decides which samples become frames: frame k (time k / fps) shows the first sample at
    or after that time. Samples must come in time order; a sample that covers several frame
    times (samples sparser than frames) is shown in each of them.
    """

    def __init__(self, fps: int) -> None:
        if fps <= 0:
            raise ValueError(f"fps must be positive, got {fps}")
        self.fps = fps
        self.next_index = 0
        self._last_ns = -1

    def frames_for(self, t_ns: int) -> int:
        """How many frames the sample at `t_ns` fills (0 when the next frame is later)."""
        if t_ns < self._last_ns:
            raise ValueError(f"samples out of time order: {t_ns} ns after {self._last_ns} ns")
        self._last_ns = t_ns
        n = 0
        while frame_time_ns(self.next_index, self.fps) <= t_ns:
            self.next_index += 1
            n += 1
        return n


def frame_count(sample_times_ns: Sequence[int], fps: int) -> int:
    """Frames a sequence of sample times (ns, ascending) gives (see `FrameClock`)."""
    clock = FrameClock(fps)
    return sum(clock.frames_for(t) for t in sample_times_ns)
