"""Headless video of runs (issue 8): frame count, size, content, and `render` from a log giving
the same frames as the live recording, also for runs that broke or were killed.

Real MuJoCo, real controller, real software OpenGL (Mesa EGL on llvmpipe) and real x264."""

from __future__ import annotations

import itertools
import math
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import imageio_ffmpeg
import numpy as np
import numpy.typing as npt
import pytest

from locoplan.exceptions import SolverFailure
from locoplan.log.reader import read_log
from locoplan.log.writer import RunLogWriter
from locoplan.plan import compile_plan
from locoplan.render.camera import TrackingCamera
from locoplan.render.from_log import render_log, samples_from_log, scene_from_log
from locoplan.render.renderer import FrameRenderer
from locoplan.render.samples import FrameClock, RenderSample
from locoplan.render.video import VideoSettings, VideoStats, write_video
from locoplan.robot.description import load_robot_description
from locoplan.scenario import load_scenario_file
from locoplan.sim.loop import ClosedLoop
from locoplan.sim.run import RunOptions, controller_settings, run_scenario, scene_for
from locoplan.sim.scene import Scene

pytestmark = pytest.mark.closed_loop

ROOT = Path(__file__).resolve().parents[1]
PICK_WALK_DROP = ROOT / "scenarios" / "pick-walk-drop.yaml"
FRAMES = npt.NDArray[np.uint8]
# x264 at CRF 20 in yuv420p: decoded frames of the same input are identical (x264 is
# deterministic), and a decoded frame is within a few grey levels of its raw render on average
# (chroma subsampling blurs edges). 3 levels mean absolute difference is far below what a
# moved robot or a different camera gives (tens of levels over thousands of pixels).
CODEC_NOISE = 3.0


def decode(path: Path) -> FRAMES:
    """Every frame of an MP4 as (n, height, width, 3) uint8."""
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    width, height = meta["size"]
    frames = [np.frombuffer(f, dtype=np.uint8).reshape(height, width, 3) for f in reader]
    return np.stack(frames) if frames else np.zeros((0, height, width, 3), np.uint8)


def mean_abs_diff(a: FRAMES, b: FRAMES) -> float:
    """Mean absolute difference in grey levels, frame by frame in int16 (a whole video in
    int64 would take half a gigabyte)."""
    assert a.shape == b.shape
    if a.ndim == 3:
        return float(np.abs(a.astype(np.int16) - b).mean())
    return float(np.mean([mean_abs_diff(x, y) for x, y in zip(a, b, strict=True)]))


@dataclass
class TwoSecondRun:
    scene: Scene
    samples: list[RenderSample]
    log_path: Path
    video: VideoStats


@pytest.fixture(scope="module")
def two_seconds(tmp_path_factory: pytest.TempPathFactory) -> TwoSecondRun:
    """The first 2 s of pick-walk-drop, closed loop, logged, with the live samples recorded as
    `run --video` does (`ClosedLoop.on_sample`) and rendered into a video."""
    tmp = tmp_path_factory.mktemp("video")
    loaded = load_scenario_file(PICK_WALK_DROP)
    scenario = loaded.scenario
    plan = compile_plan(scenario)
    desc = load_robot_description(scenario.robot)
    scene = scene_for(scenario, desc)
    settings = controller_settings(scenario, RunOptions())
    samples: list[RenderSample] = []
    log_path = tmp / "pick-walk-drop.mcap"
    with RunLogWriter(log_path, scenario_name=scenario.name, scenario_text=loaded.text) as log:
        loop = ClosedLoop(
            scene,
            desc,
            plan,
            settings,
            start_xy=(scenario.robot_start.position[0], scenario.robot_start.position[1]),
            start_yaw=math.radians(scenario.robot_start.yaw),
            log=log,
        )
        loop.on_sample = samples.append
        loop.run(2.0)
    video = write_video(scene.model, desc.trunk_body, samples, tmp / "run.mp4")
    return TwoSecondRun(scene, samples, log_path, video)


def _raw_frames(
    scene: Scene, samples: list[RenderSample], indices: set[int], hide_robot: bool = False
) -> dict[int, FRAMES]:
    """Frames `indices` rendered without encoding (optionally with every robot geom hidden:
    moved to geom group 5, which MuJoCo does not draw by default), same clock and camera."""
    model = scene.model
    if hide_robot:
        import copy

        model = copy.deepcopy(model)
        robot = [g for g in range(model.ngeom) if model.geom_bodyid[g] not in
                 (0, *scene.object_body_ids.values())]  # fmt: skip
        model.geom_group[robot] = 5
    settings = VideoSettings()
    clock, camera = FrameClock(settings.fps), TrackingCamera(settings.camera, settings.fps)
    out: dict[int, FRAMES] = {}
    k = 0
    with FrameRenderer(model, scene.robot.trunk_body, settings.width, settings.height) as fr:
        for sample in samples:
            n = clock.frames_for(sample.t_ns)
            if n:
                p, q = fr.set_state(sample)
            for _ in range(n):
                lookat = camera.update(p, q)
                if k in indices:
                    cam = settings.camera
                    frame = fr.render(
                        sample, lookat, camera.azimuth_deg, cam.elevation_deg, cam.distance
                    )
                    out[k] = frame.copy()
                k += 1
    return out


def test_two_seconds_give_sixty_distinct_frames_showing_the_robot(
    two_seconds: TwoSecondRun,
) -> None:
    stats = two_seconds.video
    frames = decode(stats.path)
    assert stats.frames == 60 and frames.shape == (60, 480, 640, 3)
    assert stats.t_first == 0.0 and stats.t_last is not None and 1.96 < stats.t_last < 2.0
    # Not blank: a lit scene has a spread of grey levels in every frame.
    assert all(float(f.std()) > 20.0 for f in frames)
    # Frames differ: the overlay's clock changes every frame; below the overlay the arms reach
    # for the box from 0.5 s on and the turn starts at 1.3 s (measured: 1.8, 5.6 and 6.9 grey
    # levels between frames 15, 30, 45 and 59; 8.6 between the first and the last).
    assert all(not np.array_equal(a, b) for a, b in itertools.pairwise(frames))
    scene_rows = slice(120, 430)  # between the text overlay and the stance squares
    for a, b in ((15, 30), (30, 45), (45, 59), (0, 59)):
        assert mean_abs_diff(frames[a][scene_rows], frames[b][scene_rows]) > 1.0, (a, b)
    # The robot is in view: hiding its geoms changes thousands of pixels in the middle of the
    # frame (the camera tracks the trunk), measured on raw renders of frames 0, 30 and 59.
    indices = {0, 30, 59}
    with_robot = _raw_frames(two_seconds.scene, two_seconds.samples, indices)
    without = _raw_frames(two_seconds.scene, two_seconds.samples, indices, hide_robot=True)
    for k in indices:
        changed = np.abs(with_robot[k].astype(np.int16) - without[k]).max(axis=2) > 30
        assert changed.sum() > 3000, k  # the trunk box alone covers ~60x90 px at 2.6 m
        rows, cols = np.nonzero(changed)
        assert 100 < rows.mean() < 380 and 160 < cols.mean() < 480  # near the centre
        # The encoder keeps the picture: decoded frame k is close to its raw render.
        assert mean_abs_diff(frames[k], with_robot[k]) < CODEC_NOISE


def test_render_from_the_log_gives_the_same_frames(
    two_seconds: TwoSecondRun, tmp_path: Path
) -> None:
    log = read_log(two_seconds.log_path)
    logged = list(samples_from_log(log))
    assert [s.t_ns for s in logged] == [s.t_ns for s in two_seconds.samples]
    assert all(
        np.array_equal(a.qpos, b.qpos) and a.stance == b.stance and a.task == b.task
        for a, b in zip(logged, two_seconds.samples, strict=True)
    )
    stats, _ = render_log(two_seconds.log_path, tmp_path / "render.mp4")
    assert stats.frames == two_seconds.video.frames
    live, rendered = decode(two_seconds.video.path), decode(stats.path)
    assert live.shape == rendered.shape
    assert mean_abs_diff(live, rendered) < CODEC_NOISE


def test_video_of_a_run_that_broke_at_t0(tmp_path: Path) -> None:
    # f_min above f_max makes the first MPC QP infeasible: the run stops at t = 0. The video
    # and the log still show that instant (the t = 0 sample is taken before the first tick).
    loaded = load_scenario_file(PICK_WALK_DROP)
    video = tmp_path / "broke.mp4"
    with pytest.raises(SolverFailure):
        run_scenario(
            loaded.scenario,
            loaded.text,
            RunOptions(out_dir=tmp_path, f_min=300.0, video=video),
        )
    assert decode(video).shape == (1, 480, 640, 3)
    log = read_log(tmp_path / "pick-walk-drop.mcap")
    assert log.complete and log.metrics is None
    stats, _ = render_log(log.path, tmp_path / "render.mp4")
    assert stats.frames == 1
    assert mean_abs_diff(decode(video), decode(stats.path)) < CODEC_NOISE


def _killed_run(tmp_path: Path) -> Iterator[Path]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "locoplan.cli", "run", str(PICK_WALK_DROP), "--out",
         str(tmp_path), "--quiet"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )  # fmt: skip
    log_path = tmp_path / "pick-walk-drop.mcap"
    deadline = time.monotonic() + 120
    try:
        # The writer flushes a chunk per second of wall time: wait for about 1 s of samples.
        while not (log_path.exists() and log_path.stat().st_size > 250_000):
            assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
            assert time.monotonic() < deadline, "the run never wrote its log"
            time.sleep(0.1)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=30)
        yield log_path
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_killed_run_is_rendered_up_to_where_its_log_ends(tmp_path: Path) -> None:
    for log_path in _killed_run(tmp_path):
        log = read_log(log_path)
        assert not log.complete
        samples = list(samples_from_log(log))
        assert len(samples) > 30
        assert log.end_time is not None and samples[-1].t <= log.end_time
        stats, _ = render_log(log_path, tmp_path / "killed.mp4")
        # The last frame shows the last sample at or after its frame time: at most one frame
        # period (1/30 s) before the end of what survived.
        assert stats.t_last is not None and 0.0 <= samples[-1].t - stats.t_last < 1.0 / 30.0
        frames = decode(stats.path)
        assert frames.shape[0] == stats.frames and stats.frames >= 20
        assert scene_from_log(log).model.nq == samples[0].qpos.shape[0]
