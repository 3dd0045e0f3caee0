"""One closed-loop run of a task script: plan -> scene -> loop -> metrics, logged to MCAP.

`run_scenario` is what `locoplan run`, `compare` and `batch` call. It never prints; progress
goes through a callback. The MCAP log is opened before the first tick and closed whatever
happens (a solver failure, a simulator instability, Ctrl-C or SIGTERM), so the file written
so far is always readable.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from locoplan import interrupt
from locoplan.control.contact import ContactLimits, foot_force_max, torsion_bound
from locoplan.control.controller import ControllerSettings
from locoplan.control.mpc import MpcSettings, force_weights
from locoplan.exceptions import LocoplanError
from locoplan.log.writer import RunLogWriter
from locoplan.metrics import (
    HELD_TOL,
    LIFT_TOL,
    REST_SPEED,
    TaskGoal,
    expectation_results,
    goal_times,
    solve_time_stats,
    torque_peaks,
    unwrap_yaw,
    yaw_difference_deg,
)
from locoplan.plan import Plan
from locoplan.render.samples import RenderSample
from locoplan.robot.description import RobotDescription, load_robot_description
from locoplan.scenario import Scenario
from locoplan.scenario.model import FixtureSpec
from locoplan.sim.live import LiveView, Pacer
from locoplan.sim.loop import RECORD_PERIOD, ClosedLoop, Push, RunRecord
from locoplan.sim.robot_plan import compile_robot_plan, plan_robot
from locoplan.sim.scene import FixtureDef, ObjectDef, Scene, build_scene

if TYPE_CHECKING:
    from locoplan.render.video import VideoStats

ON_FIXTURE_TOL = 0.03  # m: object bottom within this of a fixture's top counts as resting on it
AT_TOL = 0.05  # m: a drop `at` a point is met within this distance
LANDED_TOL = 0.01  # m: a thrown object's centre this close to its floor height has landed


@dataclass(frozen=True, slots=True)
class RunOptions:
    """How to run: strategy/model override the script's; `duration_scale` stretches every
    task time and `end` (K > 1 is slower); `mapping` and `qp_backend` select the torque mapping
    and QP solver; `pushes` are trunk disturbances (tests, robustness studies); `video` also
    renders the run into that MP4 (`locoplan.render`; up to the failure when the run breaks);
    `live` serves the log's topics to Foxglove while the run goes, paced (`locoplan.sim.live`;
    needs `log`)."""

    strategy: str | None = None
    model: str | None = None
    duration_scale: float = 1.0
    out_dir: Path = Path("runs")
    log: bool = True
    mapping: str = "wbc"
    qp_backend: str = "daqp"
    f_min: float | None = None
    pushes: tuple[Push, ...] = ()
    # The steps the controller adds (recovery and square-up, `locoplan.control.recovery`);
    # off for comparisons.
    recovery_steps: bool = True
    # The trunk's lean for a held load (`locoplan.control.lean`; off by default: measured
    # neutral, README, Envelope).
    trunk_lean: bool = False
    log_name: str | None = None
    video: Path | None = None
    live: LiveView | None = None


@dataclass(frozen=True, slots=True)
class RunResult:
    """Metrics (the contract's JSON keys), the raw record, the log path (and the video's
    stats with `RunOptions.video`)."""

    metrics: dict[str, Any]
    record: RunRecord
    plan: Plan
    log_path: Path | None
    passed: bool
    video: VideoStats | None = None


def scene_for(scenario: Scenario, desc: RobotDescription) -> Scene:
    """MuJoCo scene with the script's objects and fixtures (angles converted to radians)."""
    objects = tuple(
        ObjectDef(
            name=name,
            shape=o.shape,
            size=tuple(o.size),
            mass=o.mass,
            position=(o.position[0], o.position[1], o.position[2]),
            yaw=math.radians(o.yaw),
        )
        for name, o in scenario.objects.items()
    )
    fixtures = tuple(
        FixtureDef(
            name=name,
            kind=f.kind,
            position=(f.position[0], f.position[1], f.position[2]),
            size=(f.size[0], f.size[1], f.size[2]),
            yaw=math.radians(f.yaw),
            speed=f.speed or 0.0,
        )
        for name, f in scenario.fixtures.items()
    )
    return build_scene(desc, objects, fixtures)


def _task_goals(plan: Plan) -> list[TaskGoal]:
    goals = []
    for task in plan.tasks:
        if task.action in ("walk", "turn"):
            ref = plan.trunk_reference_at(task.end)
            goals.append(
                TaskGoal(
                    task.action,
                    task.start,
                    task.end,
                    target_position=np.asarray(ref.position, dtype=float),
                    target_yaw=float(ref.yaw),
                )
            )
        else:
            goals.append(TaskGoal(task.action, task.start, task.end, object=task.object))
    return goals


def _object_state(
    scenario: Scenario, rec: RunRecord, name: str
) -> tuple[list[float], str | None, bool]:
    """Final position, the fixture it rests on (or None) and whether it is still lifted.
    Resting on a conveyor means riding its belt: moving no faster than the belt."""
    traj = np.asarray(rec.object_positions[name])
    pos = traj[-1]
    spec = scenario.objects[name]
    half_h = spec.size[0] if spec.shape == "sphere" else spec.size[2] / 2
    speed = 0.0
    if len(traj) > 5:
        speed = float(np.linalg.norm(traj[-1] - traj[-5]) / (4 * RECORD_PERIOD))
    on: str | None = None
    for fname, f in scenario.fixtures.items():
        if _on_fixture(scenario, name, pos, fname) and speed <= abs(f.speed or 0.0) + REST_SPEED:
            on = fname
    lifted = bool(pos[2] - half_h > 0.05 and on is None)
    return [round(float(x), 4) for x in pos], on, lifted


def _over_top(fixture: FixtureSpec, p: np.ndarray) -> bool:
    """Whether the point `p` (world) lies over the fixture's top (inside its footprint)."""
    lx, ly = fixture.local_xy(float(p[0]), float(p[1]))
    return abs(lx) <= fixture.size[0] / 2 and abs(ly) <= fixture.size[1] / 2


def _on_fixture(scenario: Scenario, name: str, p: np.ndarray, fixture: str) -> bool:
    """Whether the object's centre `p` is over the fixture's top with its bottom on it."""
    spec = scenario.objects[name]
    half_h = spec.size[0] if spec.shape == "sphere" else spec.size[2] / 2
    f = scenario.fixtures[fixture]
    if f.kind == "conveyor" and f.speed:
        # A belt delivers what it carries over its downstream end: an object riding off that
        # end at belt height (its footprint still partly on the belt) is on the conveyor.
        lx, ly = f.local_xy(float(p[0]), float(p[1]))
        reach_x = f.size[0] / 2
        ahead = spec.size[0] if spec.shape == "sphere" else 0.5 * max(spec.size[0], spec.size[1])
        inside_x = -reach_x <= lx * math.copysign(1.0, f.speed) <= reach_x + ahead
        inside = inside_x and abs(ly) <= f.size[1] / 2
    else:
        inside = _over_top(f, p)
    return inside and abs(p[2] - half_h - f.size[2]) <= ON_FIXTURE_TOL


def _object_goal_times(scenario: Scenario, plan: Plan, rec: RunRecord) -> dict[int, float | None]:
    """When each manipulation task's goal was met, from the object's simulated trajectory:
    pick -> lifted LIFT_TOL above where it was at the grasp; drop -> resting on its target
    after the release (on a conveyor: riding the belt); throw -> landed after the release."""
    t = np.asarray(rec.t)
    out: dict[int, float | None] = {}
    for k, task in enumerate(plan.tasks):
        if task.action not in ("pick", "drop", "throw") or task.object is None:
            continue
        name = task.object
        traj = np.asarray(rec.object_positions.get(name, []))
        out[k] = None
        if traj.size == 0:
            continue
        kind = "grasp" if task.action == "pick" else "release"
        when = [
            te
            for te, ev, ob in rec.grasp_events
            if ev == kind and ob == name and te >= task.start - 0.1
        ]
        if not when:
            continue
        t0 = when[0]
        after = np.nonzero(t >= t0)[0]
        if after.size == 0:
            continue
        i0 = int(after[0])
        speed = np.zeros(len(t))
        speed[1:] = np.linalg.norm(np.diff(traj, axis=0), axis=1) / np.maximum(np.diff(t), 1e-9)
        for i in range(i0, len(t)):
            p = traj[i]
            if task.action == "pick":
                ok = p[2] >= traj[i0, 2] + LIFT_TOL
            elif task.action == "drop" and task.onto is not None:
                belt = scenario.fixtures[task.onto].speed or 0.0
                ok = (
                    _on_fixture(scenario, name, p, task.onto) and speed[i] <= abs(belt) + REST_SPEED
                )
            elif task.action == "drop" and task.at is not None:
                ok = np.linalg.norm(p - np.asarray(task.at)) <= AT_TOL and speed[i] <= REST_SPEED
            else:
                # Thrown: landed when it first comes down to the floor (a ball then rolls on
                # for a long time, so "at rest" would come late or never).
                spec = scenario.objects[name]
                half_h = spec.size[0] if spec.shape == "sphere" else spec.size[2] / 2
                ok = i > i0 + 5 and p[2] <= half_h + LANDED_TOL
            if ok:
                out[k] = float(t[i])
                break
    return out


def _not_held(scenario: Scenario, plan: Plan, rec: RunRecord) -> dict[str, str]:
    """The objects that a pick gripped but that were not held off their support from the
    pick's end to the start of their release (drop or throw; the run's end if none), with the
    run going on, standing, through that window: object -> what happened.

    Held means at least HELD_TOL above where the grasp closed at every sample of that window
    at which the object is over the top of the fixture it was picked from (anywhere, for one
    picked from no fixture); the pick's own goal, LIFT_TOL once, is met by a box that rises
    2 cm and goes back down. Why: a heavy box far out that the robot cannot lift stays on its
    table (or rises a centimetre or two and goes back down); the hands push it across the
    top while the robot leans, and a standing hold that puts it back "onto" the same table
    met its `placed` expectation without holding it (HECTOR envelope seeds 79021 and 81021:
    standing holds of 8.7-13.6 kg 0.29-0.40 m out had counted as successes). Only over that
    fixture: carried away from it, a box may ride lower than it was gripped and still be in
    the hands (HECTOR seed 83021: four side-carries of 4.7-4.9 kg, carried 0.8-0.9 cm above
    their grip height beside the table, had failed as not held, as had transfer-039 of seed
    82021 in its turn)."""
    t = np.asarray(rec.t)
    out: dict[str, str] = {}
    if not t.size:
        return out
    for k, task in enumerate(plan.tasks):
        if task.action != "pick" or task.object is None:
            continue
        name = task.object
        release = next(
            (r for r in plan.tasks[k + 1 :] if r.action in ("drop", "throw") and r.object == name),
            None,
        )
        t1 = release.start if release is not None else float(t[-1])
        t1 = max(t1, task.end)
        if name in rec.grasp_failures or t[-1] < t1:
            continue
        if rec.fell and (rec.fall_time is None or rec.fall_time < t1):
            continue
        grasps = [
            te
            for te, ev, ob in rec.grasp_events
            if ev == "grasp" and ob == name and te >= task.start - 0.1
        ]
        if not grasps:
            continue
        traj = np.asarray(rec.object_positions[name])
        z = traj[:, 2]
        i0 = int(np.searchsorted(t, grasps[0]))
        window = (t >= task.end - 1e-9) & (t <= t1 + 1e-9)
        if i0 >= len(z) or not window.any():
            continue
        dz = z - z[i0]
        support = [f for f in scenario.fixtures if _on_fixture(scenario, name, traj[i0], f)]
        over = np.ones(len(t), dtype=bool)
        if support:
            fixture = scenario.fixtures[support[0]]
            over = np.array([_over_top(fixture, p) for p in traj])
        low = np.nonzero(window & over & (dz < HELD_TOL))[0]
        if low.size == 0:
            continue
        rose = float(np.max(dz[i0 : int(np.nonzero(window)[0][-1]) + 1]))
        if rose < LIFT_TOL:
            out[name] = f"'{name}' never left its support (rose {rose:.3f} m after the grasp)"
        else:
            out[name] = (
                f"'{name}' was not held: {dz[low[0]]:.3f} m above where it was gripped at "
                f"{t[low[0]]:.2f} s (it rose {rose:.3f} m at most)"
            )
    return out


def compute_metrics(
    scenario: Scenario,
    plan: Plan,
    rec: RunRecord,
    options: RunOptions,
    log_path: Path | None,
) -> dict[str, Any]:
    """The metrics object of shared/cli-contract.md from a finished (or fallen) run."""
    t = np.asarray(rec.t)
    pos = np.asarray(rec.base_position).reshape(-1, 3)
    yaw = unwrap_yaw(np.asarray(rec.base_rpy).reshape(-1, 3)[:, 2]) if rec.t else np.zeros(0)
    goals = _task_goals(plan)
    objects: dict[str, dict[str, Any]] = {}
    for name in scenario.objects:
        if rec.object_positions[name]:
            p, on, _ = _object_state(scenario, rec, name)
            if name in rec.held_at_end:
                on = None  # in the hands, even if just above a fixture's top
            # Held: in the hands' grasp and not resting on anything (a grasp that never lifted
            # the object off its table does not count).
            objects[name] = {
                "position": p,
                "on": on,
                "held": name in rec.held_at_end and on is None,
            }
    times = goal_times(
        t, pos[:, :2], yaw, goals, rec.fall_time, _object_goal_times(scenario, plan, rec)
    )
    completed = bool(times) and all(x is not None for x in times) and not rec.fell
    completion = max(x for x in times if x is not None) if completed else None
    ratio, joint, peaks = torque_peaks(rec.peak_abs_torque, rec.torque_limits, rec.joint_names)
    rtf = rec.sim_time / rec.wall_time if rec.wall_time > 0 else 0.0
    metrics: dict[str, Any] = {
        "scenario": scenario.name,
        "strategy": plan.strategy,
        "model": options.model or scenario.model,
        "sim_time": round(rec.sim_time, 4),
        "wall_time": round(rec.wall_time, 3),
        "real_time_factor": round(rtf, 3),
        "completed": completed,
        "completion_time": None if completion is None else round(completion, 3),
        "fell": rec.fell,
        "fall_time": rec.fall_time,
        "yaw_difference_deg": (
            None if (d := yaw_difference_deg(t, yaw, goals)) is None or not t.size else round(d, 2)
        ),
        "peak_torque_ratio": round(ratio, 4),
        "peak_commanded_torque_ratio": round(rec.peak_commanded_ratio, 4),
        "peak_torque_joint": joint,
        "peak_torque": peaks,
        "final_base": {
            "position": [round(float(x), 4) for x in pos[-1]] if len(pos) else None,
            "yaw_deg": round(math.degrees(float(yaw[-1])), 2) if len(yaw) else None,
        },
        "objects": objects,
        "mpc_solve_ms": solve_time_stats(rec.mpc_times_s),
        "wbc_solve_ms": solve_time_stats(rec.wbc_times_s),
        "torque_clips": rec.n_clipped,
        "mpc_fallbacks": rec.n_mpc_fallbacks,
        "wbc_failures": rec.n_wbc_failures,
        "task_goal_times": [None if x is None else round(x, 3) for x in times],
        # What the planner changed in the script's timing and why (`Plan.notes`).
        "planner_notes": list(plan.notes),
    }
    expect = scenario.expect.model_dump(exclude_none=True)
    results = expectation_results(expect, metrics)
    # A pick whose hands never reached the object is a failed expectation of every script
    # (exit 1), named after the object, with the distance the hands stayed away.
    for name, gap in rec.grasp_failures.items():
        results[f"pick.{name}"] = {
            "ok": False,
            "value": f"hands {gap:.3f} m from '{name}' at the planned grasp",
            "limit": "within 0.03 m (the object may be out of reach)",
        }
    for name, what in _not_held(scenario, plan, rec).items():
        results.setdefault(
            f"pick.{name}",
            {
                "ok": False,
                "value": what,
                "limit": f"held at least {HELD_TOL:g} m up from the pick's end to its release",
            },
        )
    metrics["expectations"] = results
    metrics["passed"] = all(r["ok"] for r in results.values())
    metrics["log"] = str(log_path) if log_path is not None else None
    return metrics


def controller_settings(
    scenario: Scenario, options: RunOptions, desc: RobotDescription | None = None
) -> ControllerSettings:
    """Controller settings from the script (`mpc`, `model`), the run options and the robot
    (`desc`, else the script's): the feet's support segment (robot.yaml `foot`) bounds the
    centre of pressure, the normal-force bound per foot and the MPC's force weights scale
    with the robot's mass (`foot_force_max`, HECTOR's 250 N; `mpc.force_weights`), the
    torsion bound with the foot's length (`torsion_bound`, HECTOR's 0.02 m), the MPC's
    rigid body is robot.yaml's `mpc_body`."""
    desc = desc if desc is not None else load_robot_description(scenario.robot)
    limits = ContactLimits(
        f_max=foot_force_max(desc.total_mass),
        toe=desc.foot_toe,
        heel=desc.foot_heel,
        mu_torsion=torsion_bound(desc.foot_toe, desc.foot_heel),
    )
    if options.f_min is not None:
        limits = replace(limits, f_min=options.f_min)
    mpc = MpcSettings(
        dt=scenario.mpc.dt,
        horizon=scenario.mpc.horizon,
        f_min=limits.f_min,
        f_max=limits.f_max,
        toe=limits.toe,
        heel=limits.heel,
        mu_torsion=limits.mu_torsion,
        r_diag=force_weights(desc.total_mass),
        backend=options.qp_backend,
    )
    model = options.model or scenario.model
    return ControllerSettings(
        mapping="jacobian" if options.mapping == "jacobian" else "wbc",
        mpc_body="upper-body" if desc.mpc_body == "upper-body" else "composite",
        model="combined" if model == "combined" else "external-force",
        qp_backend=options.qp_backend,
        mpc=mpc,
        limits=limits,
        recovery_steps=options.recovery_steps,
        trunk_lean=options.trunk_lean,
    )


@dataclass(slots=True)
class _Progress:
    callback: Callable[[float, float], None] | None
    total: float
    calls: list[float] = field(default_factory=list)

    def __call__(self, t: float) -> None:
        if self.callback is not None:
            self.callback(t, self.total)


def run_scenario(
    scenario: Scenario,
    scenario_text: str,
    options: RunOptions | None = None,
    progress: Callable[[float, float], None] | None = None,
) -> RunResult:
    """Run `scenario` closed loop. Raises SolverFailure / SimulationError when the run breaks
    (the log is closed and readable), KeyboardInterrupt / SystemExit when interrupted
    (`locoplan.interrupt.Interrupted` for a deferred SIGINT / SIGTERM, at the next control
    tick or the next stage of the preparation); OSError when `options.live` cannot serve on
    its port."""
    options = options or RunOptions()
    if options.live is not None and not options.log:
        raise ValueError("a live view needs the log (RunOptions.log)")
    if options.duration_scale != 1.0:
        from locoplan.scenario.timing import scale_timing

        scenario = scale_timing(scenario, options.duration_scale)
    # The description is loaded once, for the plan and the rest (a plan error at `robot`
    # when it does not load, as `compile_robot_plan` raises it).
    desc = plan_robot(scenario)
    plan = compile_robot_plan(scenario, options.strategy, desc)
    interrupt.check()
    scene = scene_for(scenario, desc)
    settings = controller_settings(scenario, options, desc)
    interrupt.check()
    log_path: Path | None = None
    writer: RunLogWriter | None = None
    if options.log:
        options.out_dir.mkdir(parents=True, exist_ok=True)
        stem = options.log_name or (
            scenario.name if options.strategy is None else f"{scenario.name}-{plan.strategy}"
        )
        log_path = options.out_dir / f"{stem}.mcap"
        writer = RunLogWriter(
            log_path,
            scenario_name=scenario.name,
            scenario_text=scenario_text,
            # 6 decimals (um, mN) are far below what anyone reads off a plot, and rounding
            # shortens what the JSON encoder writes (measured ~25 % cheaper per message).
            json_decimals=6,
            metadata={
                "strategy": plan.strategy,
                "model": settings.model,
                "mapping": settings.mapping,
                "qp_backend": settings.qp_backend,
            },
        )
    start = scenario.robot_start
    with writer if writer is not None else contextlib.nullcontext():
        loop = ClosedLoop(
            scene,
            desc,
            plan,
            settings,
            start_xy=(start.position[0], start.position[1]),
            start_yaw=math.radians(start.yaw),
            log=writer,
            pushes=options.pushes,
        )
        interrupt.check()  # the controller's kernels are compiled or loaded by now
        if writer is not None and options.live is not None:
            writer.serve(options.live.port, options.live.host)
            if options.live.wait > 0.0:
                writer.wait_for_subscriber(options.live.wait)
                interrupt.check()
            loop.pacer = Pacer(writer, options.live.pace)
        samples: list[RenderSample] = []
        rec = _run_recording(loop, plan.t_end, _Progress(progress, plan.t_end), options, samples)
        metrics = compute_metrics(scenario, plan, rec, options, log_path)
        if writer is not None:
            writer.finish(metrics)
    video = None if options.video is None else _write_video(scene, samples, options.video)
    return RunResult(metrics, rec, plan, log_path, bool(metrics["passed"]), video)


# -- run --video (locoplan.render) -----------------------------------------------------------
def _run_recording(
    loop: ClosedLoop,
    t_end: float,
    progress: _Progress,
    options: RunOptions,
    samples: list[RenderSample],
) -> RunRecord:
    """`loop.run`, collecting the video's samples with `options.video`; when the run breaks,
    the video up to the failure is written before the error goes on (rendering waits until
    the loop ends, so it never counts in the run's wall time)."""
    if options.video is None:
        return loop.run(t_end, progress)
    loop.on_sample = samples.append
    try:
        return loop.run(t_end, progress)
    except LocoplanError:
        # The run's own error is what the caller must see, not a rendering problem.
        with contextlib.suppress(LocoplanError, OSError):
            _write_video(loop.scene, samples, options.video)
        raise


def _write_video(scene: Scene, samples: list[RenderSample], path: Path) -> VideoStats:
    from locoplan.render.video import write_video

    return write_video(scene.model, scene.robot.trunk_body, samples, path)
