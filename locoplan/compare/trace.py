"""What the comparison plots need from one run, as plain arrays that cross process boundaries.

A `RunTrace` is built in the process that ran the simulation (from its `RunResult`, whose
`Plan` need not be picklable) and sent back to the parent, which draws the plots. Samples
follow the closed loop's record (every 10 ms); angles are in radians, positions in m (world).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from locoplan.metrics import unwrap_yaw
from locoplan.plan import Plan
from locoplan.robot.description import RobotDescription
from locoplan.scenario import Scenario
from locoplan.sim.loop import RunRecord

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]

LIFTED_TOL = 0.02  # m: an object this far above its start height is off its support
PLAN_SAMPLE = 0.01  # s between samples of the planned contact flags (the record's period)


@dataclass(frozen=True, slots=True)
class TaskWindow:
    """One planned task: scenario index, action, start and end (s), object (or None)."""

    index: int
    action: str
    start: float
    end: float
    object: str | None = None


@dataclass(frozen=True, slots=True)
class FixtureOutline:
    """A fixture seen from above: centre (x, y) m, footprint (size_x, size_y) m in its own
    frame, yaw rad, top height m."""

    name: str
    kind: str
    center_xy: tuple[float, float]
    size_xy: tuple[float, float]
    yaw: float
    top: float

    def corners(self) -> FloatArray:
        """Footprint corners (5, 2) m world, closed (first corner repeated)."""
        hx, hy = self.size_xy[0] / 2, self.size_xy[1] / 2
        local = np.array([[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy], [hx, hy]])
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        R = np.array([[c, -s], [s, c]])
        return np.asarray(local @ R.T + np.asarray(self.center_xy), dtype=float)


@dataclass(frozen=True, slots=True, eq=False)
class RunTrace:
    """One run's time series for plots, sampled at `t` (n,) s.

    `base_position` (n, 3) m and `base_rpy` (n, 3) rad (yaw unwrapped) of the trunk from
    MuJoCo; `yaw_reference` (n,) rad the plan's trunk yaw; `object_positions[name]` (n, 3) m;
    `object_lifted[name]` (n,) whether the object is more than LIFTED_TOL above its start
    height in the simulation; `object_targets[name]` (3,) m where the plan puts the object
    (placed centre, or the ballistic landing point of a throw; only objects with one);
    `joint_torque` (n, n_joints) N m applied by MuJoCo with
    `torque_limits` (n_joints,) N m; `t_plan` (m,) s a grid over the whole plan (every
    PLAN_SAMPLE s up to `t_end`, also past a fall) with the planned contact flags
    `feet_stance` (m, 2), `hands_contact` (m, 2) and `object_held` (m,) (columns left,
    right); `tasks` the planned
    task windows; `pick_start` / `drop_start` (s) the first pick and the drop or throw of the
    same object (None without such a pair); `fall_time` (s) or None; `completion_time` (s) or
    None; `t_end` the planned end (s).
    """

    label: str
    t: FloatArray
    base_position: FloatArray
    base_rpy: FloatArray
    yaw_reference: FloatArray
    object_positions: Mapping[str, FloatArray]
    object_lifted: Mapping[str, BoolArray]
    object_targets: Mapping[str, tuple[float, float, float]]
    joint_torque: FloatArray
    torque_limits: FloatArray
    joint_names: tuple[str, ...]
    leg_joints: tuple[tuple[str, ...], tuple[str, ...]]
    t_plan: FloatArray
    feet_stance: BoolArray
    hands_contact: BoolArray
    object_held: BoolArray
    tasks: tuple[TaskWindow, ...]
    pick_start: float | None
    drop_start: float | None
    release_kind: str | None
    fall_time: float | None
    completion_time: float | None
    t_end: float

    @property
    def yaw(self) -> FloatArray:
        """Measured trunk yaw (n,) rad, unwrapped."""
        return np.asarray(self.base_rpy[:, 2])

    def yaw_at(self, when: float) -> float:
        """Measured trunk yaw (rad) at `when` (s), linear between samples."""
        return float(np.interp(when, self.t, self.yaw))

    @property
    def yaw_difference_deg(self) -> float | None:
        """|yaw(drop start) - yaw(pick start)| in degrees (the paper's measure); None without a
        pick..drop pair or when the run ended (fell) before the drop start."""
        if self.pick_start is None or self.drop_start is None or not self.t.size:
            return None
        if self.drop_start > self.t[-1] + 1e-9:
            return None
        return abs(math.degrees(self.yaw_at(self.drop_start) - self.yaw_at(self.pick_start)))


def pick_drop_pair(plan: Plan) -> tuple[float, float, str] | None:
    """Planned start (s) of the first pick and of the drop or throw of the same object, and
    the release kind; None when the plan has no such pair (metrics use the same rule)."""
    for i, task in enumerate(plan.tasks):
        if task.action != "pick" or task.object is None:
            continue
        for later in plan.tasks[i + 1 :]:
            if later.action in ("drop", "throw") and later.object == task.object:
                return task.start, later.start, later.action
    return None


def fixture_outlines(scenario: Scenario) -> tuple[FixtureOutline, ...]:
    """The scenario's fixtures as top-view outlines (angles converted to radians)."""
    return tuple(
        FixtureOutline(
            name=name,
            kind=f.kind,
            center_xy=(f.position[0], f.position[1]),
            size_xy=(f.size[0], f.size[1]),
            yaw=math.radians(f.yaw),
            top=f.size[2],
        )
        for name, f in scenario.fixtures.items()
    )


def _targets(plan: Plan, names: tuple[str, ...]) -> dict[str, tuple[float, float, float]]:
    out = {}
    for name in names:
        try:
            target = plan.object_target(name)
        except KeyError:
            continue
        if target.kind in ("place", "throw") and target.position is not None:
            x, y, z = target.position
            out[name] = (float(x), float(y), float(z))
    return out


def trace_from_run(
    label: str,
    plan: Plan,
    record: RunRecord,
    desc: RobotDescription,
    completion_time: float | None,
) -> RunTrace:
    """Collect the plot series of one finished (or fallen) run."""
    t = np.asarray(record.t, dtype=float)
    n = t.size
    rpy = np.asarray(record.base_rpy, dtype=float).reshape(n, 3)
    if n:
        rpy[:, 2] = unwrap_yaw(rpy[:, 2])
    objects = {
        name: np.asarray(p, dtype=float).reshape(n, 3)
        for name, p in record.object_positions.items()
    }
    lifted = {
        name: (p[:, 2] > p[0, 2] + LIFTED_TOL) if n else np.zeros(0, dtype=bool)
        for name, p in objects.items()
    }
    n_joints = len(record.joint_names)
    pair = pick_drop_pair(plan)
    t_plan = np.arange(0.0, plan.t_end + 0.5 * PLAN_SAMPLE, PLAN_SAMPLE)
    m = t_plan.size
    return RunTrace(
        label=label,
        t=t,
        base_position=np.asarray(record.base_position, dtype=float).reshape(n, 3),
        base_rpy=rpy,
        yaw_reference=np.asarray(plan.trunk_reference(t).yaw, dtype=float) if n else np.zeros(0),
        object_positions=objects,
        object_lifted=lifted,
        object_targets=_targets(plan, tuple(objects)),
        joint_torque=np.asarray(record.joint_torque, dtype=float).reshape(-1, n_joints),
        torque_limits=np.asarray(record.torque_limits, dtype=float),
        joint_names=tuple(record.joint_names),
        leg_joints=(
            tuple(desc.joint_names[i] for i in desc.leg_joint_indices[0]),
            tuple(desc.joint_names[i] for i in desc.leg_joint_indices[1]),
        ),
        t_plan=t_plan,
        feet_stance=np.asarray(plan.contact_flags(t_plan), dtype=bool).reshape(m, 2),
        hands_contact=np.asarray(plan.hand_contact_flags(t_plan), dtype=bool).reshape(m, 2),
        object_held=np.asarray(plan.object_held(t_plan), dtype=bool).reshape(m),
        tasks=tuple(
            TaskWindow(task.index, task.action, task.start, task.end, task.object)
            for task in plan.tasks
        ),
        pick_start=None if pair is None else pair[0],
        drop_start=None if pair is None else pair[1],
        release_kind=None if pair is None else pair[2],
        fall_time=record.fall_time,
        completion_time=completion_time,
        t_end=plan.t_end,
    )
