"""The closed loop: plan -> controller -> MuJoCo, logged to MCAP as it goes.

Physics runs at the scene's timestep (1 ms); the controller runs every physics step (perfect
state estimation, as the paper assumes). What metrics need is recorded into a `RunRecord`
(pure arrays, `locoplan.metrics` turns them into numbers); what a person needs to look at is
written to the MCAP log as the run goes, so a crash or Ctrl-C leaves a readable file.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import mujoco
import numpy as np
import numpy.typing as npt
from numba import njit

from locoplan.control.controller import (
    ControllerSettings,
    ControlOutput,
    LocoManipulationController,
)
from locoplan.exceptions import SimulationError, SolverFailure
from locoplan.interrupt import STATE as _INTERRUPT
from locoplan.interrupt import Interrupted
from locoplan.log.writer import RunLogWriter
from locoplan.plan import Plan
from locoplan.plan.hand_paths import default_waypoint
from locoplan.render.samples import RenderSample, TaskTimeline
from locoplan.render.view_log import ViewLogger, sample_from_data
from locoplan.robot.description import RobotDescription
from locoplan.robot.pinocchio_model import PinocchioRobot
from locoplan.sim.backend import MujocoBackend
from locoplan.sim.grasp import ConveyorDrive, GraspManager
from locoplan.sim.scene import Scene

FloatArray = npt.NDArray[np.float64]

RECORD_PERIOD = 0.01  # s between recorded samples (metrics) and transform messages
TILT_LIMIT = math.radians(60.0)
_COS_TILT_LIMIT = math.cos(TILT_LIMIT)
_WXYZ_TO_XYZW = np.array([1, 2, 3, 0])


@dataclass(frozen=True, slots=True)
class Push:
    """A force (N, world) applied to the trunk during [start, start + duration)."""

    start: float
    duration: float
    force: tuple[float, float, float]


@dataclass(slots=True)
class RunRecord:
    """What a run produced, sampled every RECORD_PERIOD (plus per-tick maxima).

    Per sample: time (s), trunk origin position (3,) and roll/pitch/yaw (rad) from MuJoCo's
    free joint, each object's position (3,), the torques MuJoCo applied (n_joints,) and the
    planned stance flags (L, R). The per-joint peaks are sized from `torque_limits`."""

    joint_names: tuple[str, ...]
    torque_limits: FloatArray
    t: list[float] = field(default_factory=list)
    base_position: list[FloatArray] = field(default_factory=list)
    base_rpy: list[tuple[float, float, float]] = field(default_factory=list)
    object_positions: dict[str, list[FloatArray]] = field(default_factory=dict)
    joint_torque: list[FloatArray] = field(default_factory=list)
    stance: list[tuple[bool, bool]] = field(default_factory=list)
    peak_abs_torque: FloatArray = field(default_factory=lambda: np.zeros(0))
    peak_torque_time: FloatArray = field(default_factory=lambda: np.zeros(0))
    mpc_times_s: list[float] = field(default_factory=list)
    wbc_times_s: list[float] = field(default_factory=list)
    tick_split_s: dict[str, float] = field(default_factory=dict)
    n_ticks: int = 0
    # (time, kind, object) for grasp, grasp_failed and release.
    grasp_events: list[tuple[float, str, str]] = field(default_factory=list)
    # For a failed grasp: the object -> the hands' largest distance (m) from its surface.
    grasp_failures: dict[str, float] = field(default_factory=dict)
    held_at_end: set[str] = field(default_factory=set)
    n_clipped: int = 0
    # max over ticks and joints of |commanded tau| / limit, before the last-guard clip
    peak_commanded_ratio: float = 0.0
    n_mpc_fallbacks: int = 0
    n_wbc_failures: int = 0
    fell: bool = False
    fall_time: float | None = None
    sim_time: float = 0.0
    wall_time: float = 0.0
    error: str | None = None

    def __post_init__(self) -> None:
        n = len(self.torque_limits)
        if self.peak_abs_torque.shape != (n,):
            self.peak_abs_torque = np.zeros(n)
        if self.peak_torque_time.shape != (n,):
            self.peak_torque_time = np.zeros(n)


# Explicit signature (any layout): compiled or loaded from the cache at import.
@njit(
    "Tuple((float64, boolean))(float64[:], float64[:], float64[:], float64[:], float64[:],"
    " float64, float64[:], float64[:])",
    cache=True,
    error_model="numpy",  # x / 0 gives inf or NaN as in numpy, no exception
)
def _tick_checks(
    tau: FloatArray,
    limits: FloatArray,
    applied: FloatArray,
    peak_abs: FloatArray,
    peak_time: FloatArray,
    t: float,
    qpos: FloatArray,
    qvel: FloatArray,
) -> tuple[float, bool]:
    """A control tick's bookkeeping in one call: max |tau| / limit of the commanded torques
    (-1 when one is NaN: NaN never raises a peak), the applied torques' peaks `peak_abs` and
    their times `peak_time` (updated in place, at `t`), and whether qpos and qvel are finite.
    The same operations as numpy's abs, divide, max and isfinite, so the same numbers."""
    ratio = 0.0
    has_nan = False
    for i in range(tau.size):
        r = abs(tau[i]) / limits[i]
        if r != r:
            has_nan = True
        elif r > ratio:
            ratio = r
    for i in range(applied.size):
        a = abs(applied[i])
        if a > peak_abs[i]:
            peak_abs[i] = a
            peak_time[i] = t
    finite = True
    for x in qpos:
        if not np.isfinite(x):
            finite = False
    for x in qvel:
        if not np.isfinite(x):
            finite = False
    return (-1.0 if has_nan else ratio), finite


def _rpy_wxyz(qw: float, qx: float, qy: float, qz: float) -> tuple[float, float, float]:
    roll = math.atan2(2 * (qw * qx + qy * qz), 1 - 2 * (qx * qx + qy * qy))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (qw * qy - qz * qx))))
    yaw = math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
    return roll, pitch, yaw


class ClosedLoop:
    """Owns the backend, the controller and the record for one run."""

    def __init__(
        self,
        scene: Scene,
        desc: RobotDescription,
        plan: Plan,
        settings: ControllerSettings,
        start_xy: tuple[float, float] = (0.0, 0.0),
        start_yaw: float = 0.0,
        log: RunLogWriter | None = None,
        pushes: tuple[Push, ...] = (),
        control_period: float = 0.002,
    ) -> None:
        self.scene = scene
        self.desc = desc
        self.plan = plan
        self.backend = MujocoBackend(scene)
        tracks = plan.manipulation.tracks
        # Arms start in the nominal keyframe unless the plan starts a hand elsewhere (tucked).
        moved = any(tr.initial != default_waypoint(i, plan.geometry) for i, tr in enumerate(tracks))
        self.backend.reset(
            start_xy, start_yaw, tuple(tr.initial.point for tr in tracks) if moved else None
        )
        # The controller runs every `control_decimation` physics steps and its torques are
        # held in between (a zero-order hold, as on a real robot's control bus).
        self.control_decimation = max(1, round(control_period / self.backend.dt))
        self.controller = LocoManipulationController(PinocchioRobot(desc), desc, plan, settings)
        self.log = log
        self.pushes = pushes
        self.grasp = GraspManager(scene, plan.holds, plan.geometry.grasp_tolerance)
        self.conveyor = ConveyorDrive(scene)
        self.record = RunRecord(
            joint_names=tuple(desc.joint_names),
            torque_limits=np.asarray(desc.torque_limits, dtype=float).copy(),
        )
        for name in scene.object_body_ids:
            self.record.object_positions[name] = []
        m = scene.model
        robot_bodies = [
            (i, mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, i) or f"body{i}")
            for i in range(1, m.nbody)
            if not (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, i) or "").startswith("object_")
        ]
        # Per-run constants of the recorded samples (the /tf frames, the joint names).
        self._robot_body_ids = np.array([i for i, _ in robot_bodies], dtype=np.intp)
        self._robot_body_names = [name for _, name in robot_bodies]
        self._joint_names = list(desc.joint_names)
        self._object_bodies = list(scene.object_body_ids.items())
        self._next_record = 0.0
        self._events = plan.events
        self._next_event = 0
        self._init_view()
        # Called with the simulation time after each recorded sample (`locoplan.sim.live`:
        # publishes to the live view and sleeps to keep pace); None costs one test per sample.
        self.pacer: Callable[[float], None] | None = None
        if log is not None:
            log.joint_limits(
                list(desc.joint_names),
                np.asarray(desc.torque_limits).tolist(),
                np.asarray(desc.q_lower).tolist(),
                np.asarray(desc.q_upper).tolist(),
            )

    def _apply_pushes(self, t: float) -> None:
        f = np.zeros(3)
        for p in self.pushes:
            if p.start <= t < p.start + p.duration:
                f += np.asarray(p.force)
        self.backend.set_trunk_force(f)

    def _log_mpc(self, t: float, out: ControlOutput) -> None:
        """Every MPC update: first-step wrenches, the planned forces over the horizon, the
        predicted trunk trajectory, status and times."""
        assert self.log is not None and out.mpc is not None
        m = out.mpc
        X = np.asarray(m.X)
        self.log.json(
            "/mpc/solution",
            t,
            {
                "ok": m.ok,
                "status": m.status,
                "fallback": m.fallback,
                "iterations": m.iterations,
                "forces_world": m.forces_world,
                "moments_world": m.moments_world,
                "planned_U": np.asarray(m.U),
                "predicted_com": X[:, 3:6],
                "predicted_rpy_deg": np.degrees(X[:, 0:3]),
                "update_ms": out.mpc_time_s * 1e3,
                "build_ms": m.build_time_s * 1e3,
                "solve_ms": m.solve_time_s * 1e3,
            },
        )

    def _log_plan_events(self, t: float) -> None:
        """Plan events (task start/end, lift-off, touchdown, grasp, release) as they happen."""
        assert self.log is not None
        while self._next_event < len(self._events) and self._events[self._next_event].t <= t:
            ev = self._events[self._next_event]
            self.log.event(ev.t, ev.kind, task_index=ev.task_index, detail=ev.detail)
            self._next_event += 1

    def _log_added_steps(self, t: float, start: int) -> None:
        """The steps the controller added to the plan's schedule since the `start`-th (a
        recovery step for a capture point outside the soles, or a square-up step), as
        `step_added` events: foot, reason, lift-off and touchdown times, target."""
        assert self.log is not None
        for st in self.controller.recovery.steps[start:]:
            self.log.event(
                t,
                "step_added",
                detail="LR"[st.foot],
                reason=st.reason,
                liftoff=st.liftoff,
                touchdown=st.touchdown,
                target=[float(x) for x in st.target[:2]],
            )

    def _record(self, t_tick: float, t: float, out: ControlOutput, applied: FloatArray) -> None:
        """One recorded sample at `t` (s, after the physics step of the tick that started at
        `t_tick`): the record's trunk and object poses, and with a log the link poses, joint
        states, trunk, contact forces, WBC output, contact schedule and the view topics."""
        rec = self.record
        d = self.backend.data
        qpos = d.qpos
        pos = np.array(qpos[0:3])
        rpy = _rpy_wxyz(*qpos[3:7].tolist())
        rec.t.append(t)
        rec.base_position.append(pos)
        rec.base_rpy.append(rpy)
        xpos = d.xpos
        for name, bid in self._object_bodies:
            rec.object_positions[name].append(np.array(xpos[bid]))
        log = self.log
        if log is None:
            if self.on_sample is not None:
                self.on_sample(self._sample(t, out.stance))
            return
        self._log_plan_events(t)
        ids = self._robot_body_ids
        # `take` gathers the same rows as fancy indexing (xpos[ids], xquat[ids][:, perm]) at a
        # quarter of the cost: about 2 us less a sample.
        log.frame_transforms_arrays(
            t,
            "world",
            self._robot_body_names,
            xpos.take(ids, axis=0),
            d.xquat.take(ids, axis=0).take(_WXYZ_TO_XYZW, axis=1),
        )
        n = len(self._joint_names)
        log.joint_states(t, self._joint_names, qpos[7 : 7 + n], d.qvel[6 : 6 + n], applied)
        log.json(
            "/robot/base",
            t,
            {"position": pos, "rpy_deg": np.degrees(np.asarray(rpy))},
        )
        forces = self.backend.foot_contact_forces()
        log.json("/contact/measured", t, {"force_world": forces})
        self._view_sample(t, out, applied, forces)
        if out.wbc is not None:
            w = out.wbc
            log.json(
                "/wbc",
                t_tick,
                {
                    "ok": w.ok,
                    "status": w.status,
                    "iterations": w.iterations,
                    "tau": out.tau,
                    "tau_clipped": out.tau_clipped,
                    "n_clipped": out.n_clipped,
                    "delta_base_acc": w.delta_base,
                    # (stance contacts, 5): an array, so the writer rounds it as the rest
                    "contact_w5": np.asarray(w.w5, dtype=float).reshape(-1, 5),
                    "tick_ms": out.wbc_time_s * 1e3,
                    "build_ms": w.build_time_s * 1e3,
                    "solve_ms": w.solve_time_s * 1e3,
                },
            )
        log.json(
            "/contact/schedule",
            t_tick,
            {"stance": list(out.stance), "wrench_world": out.wrench_world},
        )

    def run(
        self,
        t_end: float,
        progress: Callable[[float], None] | None = None,
    ) -> RunRecord:
        """Simulate until `t_end` (s) or a fall. Raises SolverFailure / SimulationError, and
        `locoplan.interrupt.Interrupted` at the first control tick after a deferred SIGINT /
        SIGTERM (the record and the log then hold everything up to that tick)."""
        rec = self.record
        be = self.backend
        d = be.data
        log = self.log
        controller = self.controller
        grasp = self.grasp
        perf_counter = time.perf_counter
        dt = be.dt
        n_steps = round(t_end / dt)
        decimation = self.control_decimation
        limits = rec.torque_limits
        wall0 = perf_counter()
        # Wall time per part, accumulated in locals (cheaper than a dict in the hot loop).
        t_physics = t_dynamics = t_mpc = t_wbc = t_logging = 0.0
        n_ticks = 0
        next_record = self._next_record
        last_progress = 0.0
        pacer = self.pacer
        interrupt = _INTERRUPT
        self._view_start()
        try:
            out = None
            n_clipped = 0  # clipped joints of the held torques, counted per physics step
            n_added = len(controller.recovery.steps)  # steps the controller added, logged
            applied = np.zeros(len(limits))
            for i in range(n_steps):
                t = d.time
                # Everything but the physics step runs at the control rate: the torques are
                # held between control ticks (so is what the actuators apply), and grasps,
                # belts, pushes and the fall check need no finer timing than 2 ms.
                tick = out is None or i % decimation == 0
                if tick:
                    if interrupt.signum:
                        raise Interrupted(interrupt.signum)
                    q, v = be.robot_qv()
                    out = controller.step(t, q, v, grasp.hand_load(d) if grasp.holds else None)
                    if log is not None and len(controller.recovery.steps) > n_added:
                        self._log_added_steps(t, n_added)
                    n_added = len(controller.recovery.steps)
                    t_dynamics += out.dynamics_time_s
                    t_mpc += out.mpc_time_s
                    t_wbc += out.wbc_time_s
                    if out.mpc is not None:
                        rec.mpc_times_s.append(out.mpc_time_s)
                        if log is not None:
                            t_l = perf_counter()
                            self._log_mpc(t, out)
                            t_logging += perf_counter() - t_l
                        if out.mpc.fallback != "none":
                            rec.n_mpc_fallbacks += 1
                    if out.wbc is not None:
                        rec.wbc_times_s.append(out.wbc_time_s)
                        if not out.wbc.ok:
                            rec.n_wbc_failures += 1
                    if grasp.holds:
                        for kind, fields in grasp.update(t, d):
                            rec.grasp_events.append((t, kind, str(fields["object"])))
                            if kind == "grasp_failed":
                                rec.grasp_failures[str(fields["object"])] = float(fields["gap_m"])  # type: ignore[arg-type]
                            if log is not None:
                                log.event(t, kind, **fields)
                        grasp.palm_torques(d)
                    if self.conveyor.belts:
                        self.conveyor.apply(d, grasp.held_objects())
                    if self.pushes:
                        self._apply_pushes(t)
                    n_clipped = out.n_clipped
                    t_p = perf_counter()
                    be.step(out.tau_clipped)
                    t_physics += perf_counter() - t_p
                else:
                    t_p = perf_counter()
                    be.step_held()
                    t_physics += perf_counter() - t_p
                rec.n_clipped += n_clipped
                n_ticks += 1
                assert out is not None
                if tick:
                    applied = be.applied_torques()
                    ratio, finite = _tick_checks(
                        out.tau,
                        limits,
                        applied,
                        rec.peak_abs_torque,
                        rec.peak_torque_time,
                        t,
                        d.qpos,
                        d.qvel,
                    )
                    rec.peak_commanded_ratio = max(rec.peak_commanded_ratio, ratio)
                    if not finite:
                        raise SimulationError(t, "non-finite state (NaN or inf)")
                if t + 1e-9 >= next_record:
                    t_l = perf_counter()
                    next_record += RECORD_PERIOD
                    rec.joint_torque.append(applied)
                    rec.stance.append(out.stance)
                    self._record(t, d.time, out, applied)
                    t_logging += perf_counter() - t_l
                    if pacer is not None:
                        pacer(d.time)
                if tick and not rec.fell and self._fallen():
                    rec.fell = True
                    rec.fall_time = d.time
                    if log is not None:
                        log.event(d.time, "fall", height=float(d.qpos[2]))
                    break
                if progress is not None and d.time - last_progress >= 0.05:
                    last_progress = d.time
                    progress(d.time)
        except (SolverFailure, SimulationError) as exc:
            rec.error = str(exc)
            raise
        finally:
            self._next_record = next_record
            rec.n_ticks += n_ticks
            rec.held_at_end = self.grasp.held_objects()
            rec.sim_time = be.time
            rec.wall_time = perf_counter() - wall0
            rec.tick_split_s = {
                "physics": t_physics,
                "dynamics": t_dynamics,
                "mpc": t_mpc,
                "wbc": t_wbc,
                "logging": t_logging,
            }
        return rec

    # -- what the video and the Foxglove 3D scene need (locoplan.render) --------------------
    def _init_view(self) -> None:
        """`on_sample` receives every recorded `RenderSample` (t = 0 first), e.g. a video
        recorder; with a log, `ViewLogger` writes them and the 3D scene topics."""
        self.on_sample: Callable[[RenderSample], None] | None = None
        self._timeline = TaskTimeline.from_plan(self.plan)
        self._view = None if self.log is None else ViewLogger(self.scene, self.plan, self.log)

    def _view_start(self) -> None:
        d = self.backend.data
        t = self.backend.time
        stance = (bool(self.plan.foot_stance(0, t)), bool(self.plan.foot_stance(1, t)))
        sample = sample_from_data(t, d, stance, self._timeline.label_at(t))
        if self.on_sample is not None:
            self.on_sample(sample)
        if self._view is not None:
            self._view.start(sample, d)

    def _sample(self, t: float, stance: tuple[bool, bool]) -> RenderSample:
        return sample_from_data(t, self.backend.data, stance, self._timeline.label_at(t))

    def _view_sample(
        self, t: float, out: ControlOutput, tau: FloatArray, forces: FloatArray
    ) -> None:
        """The sample at `t` to `on_sample` and the view topics; `forces` (2, 3) N measured."""
        sample = self._sample(t, out.stance)
        if self.on_sample is not None:
            self.on_sample(sample)
        if self._view is not None:
            com = None if out.mpc is None else np.asarray(out.mpc.X)[:, 3:6]
            self._view.sample(sample, self.backend.data, forces, com, tau)

    def _fallen(self) -> bool:
        qpos = self.backend.data.qpos
        z, _, qx, qy = qpos[2:6].tolist()
        # Tilt of the trunk's z axis from vertical: cos(tilt) = 1 - 2 (qx^2 + qy^2).
        cos_tilt = 1.0 - 2.0 * (qx * qx + qy * qy)
        return bool(z < self.desc.fall_height or cos_tilt < _COS_TILT_LIMIT)
