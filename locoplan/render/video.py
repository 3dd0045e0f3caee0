"""MP4 videos of runs: samples in, H.264 frames out.

`VideoRecorder` is the one path from samples to a file, used by ``locoplan run --video``
(samples collected live by the loop's `on_sample` hook, rendered when the run ends, so
rendering does not count in the run's wall time) and by ``locoplan render`` (samples read
back from the log's ``/sim/qpos``): `FrameClock` picks the samples that become frames,
`TrackingCamera` moves the view once per frame, `FrameRenderer` draws, and the frames are
piped to the ffmpeg binary that the imageio-ffmpeg wheel ships (libx264, yuv420p, CRF 20),
which encodes in its own process, in parallel with the rendering.

The file is written as ``<name>.part.mp4`` and renamed when complete, so a reader never sees
a half-written video.
"""

from __future__ import annotations

import contextlib
import os
import statistics
import time
from collections.abc import Generator, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from locoplan.render.camera import CameraSettings, TrackingCamera
from locoplan.render.errors import RenderError
from locoplan.render.renderer import FrameRenderer, UInt8Image
from locoplan.render.samples import FrameClock, RenderSample, frame_time_ns


@dataclass(frozen=True, slots=True)
class VideoSettings:
    """Frame size (pixels, even), frames per second, camera and encoder quality (x264 CRF:
    lower is better and bigger; 20 is visually clean for this flat-shaded scene)."""

    width: int = 640
    height: int = 480
    fps: int = 30
    camera: CameraSettings = field(default_factory=CameraSettings)
    crf: int = 20
    preset: str = "veryfast"


@dataclass(frozen=True, slots=True)
class VideoStats:
    """What was written: `frames` frames of `width` x `height` at `fps`, covering simulation
    times `t_first`..`t_last` (s, sample times of the first and last frame; None without
    frames); the GL backend; render time per frame (ms, median and mean) and the whole wall
    time (s) including encoding."""

    path: Path
    frames: int
    width: int
    height: int
    fps: int
    t_first: float | None
    t_last: float | None
    backend: str
    render_ms_median: float
    render_ms_mean: float
    wall_s: float


def _ffmpeg_writer(path: Path, settings: VideoSettings) -> Generator[None, Any, None]:
    try:
        import imageio_ffmpeg
    except ImportError as exc:
        raise RenderError(
            "encoder", "the video encoder is missing: pip install 'imageio-ffmpeg~=0.8'", path
        ) from exc
    writer: Generator[None, Any, None] = imageio_ffmpeg.write_frames(
        str(path),
        (settings.width, settings.height),
        fps=settings.fps,
        codec="libx264",
        pix_fmt_in="rgb24",
        pix_fmt_out="yuv420p",
        quality=None,
        bitrate=None,
        macro_block_size=2,
        ffmpeg_log_level="error",
        output_params=["-crf", str(settings.crf), "-preset", settings.preset],
    )
    writer.send(None)  # starts ffmpeg
    return writer


class VideoRecorder:
    """Turns `RenderSample`s (in time order) into an MP4 at `path` (see the module docstring).

    `model` is the compiled scene the samples' qpos belong to; `trunk_body` the body the
    camera follows. Use as a context manager or call `close`, which finishes the file and
    returns its `VideoStats`. RenderError when OpenGL or the encoder is missing, or when
    no sample reached a frame (an empty video is not written).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        trunk_body: str,
        path: str | Path,
        settings: VideoSettings | None = None,
    ) -> None:
        self.settings = settings or VideoSettings()
        s = self.settings
        self.path = Path(path)
        self._part = self.path.with_name(self.path.stem + ".part" + (self.path.suffix or ".mp4"))
        self._wall0 = time.perf_counter()
        self._renderer = FrameRenderer(model, trunk_body, s.width, s.height)
        self._clock = FrameClock(s.fps)
        self._camera = TrackingCamera(s.camera, s.fps)
        self._writer: Generator[None, Any, None] | None = None
        self.frames = 0
        self._t_first: float | None = None
        self._t_last: float | None = None
        self._closed = False

    def __enter__(self) -> VideoRecorder:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, *rest: object) -> None:
        if exc_type is None and not self._closed:
            self.close()
        else:
            self.abort()

    def add(self, sample: RenderSample) -> None:
        """Render the frames `sample` fills (none, one, or several when samples are sparser
        than frames)."""
        n = self._clock.frames_for(sample.t_ns)
        if n == 0:
            return
        trunk_p, trunk_q = self._renderer.set_state(sample)
        cam = self.settings.camera
        for _ in range(n):
            lookat = self._camera.update(trunk_p, trunk_q)
            frame = self._renderer.render(
                sample, lookat, self._camera.azimuth_deg, cam.elevation_deg, cam.distance
            )
            self._write(frame)
            if self._t_first is None:
                self._t_first = sample.t
            self._t_last = sample.t

    def add_all(self, samples: Iterable[RenderSample]) -> None:
        """`add` every sample of `samples`."""
        for sample in samples:
            self.add(sample)

    def _write(self, frame: UInt8Image) -> None:
        if self._writer is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._writer = _ffmpeg_writer(self._part, self.settings)
        try:
            self._writer.send(np.ascontiguousarray(frame).tobytes())
        except (OSError, RuntimeError) as exc:
            raise RenderError("encoder", f"ffmpeg stopped: {exc}", self.path) from exc
        self.frames += 1

    def close(self) -> VideoStats:
        """Finish the file (renamed into place) and return its stats."""
        if self._closed:
            raise RenderError("encoder", "VideoRecorder already closed", self.path)
        self._closed = True
        self._renderer.close()
        if self._writer is None:
            raise RenderError("log", "no sample to render: the video would be empty", self.path)
        try:
            self._writer.close()
        except (OSError, RuntimeError) as exc:
            raise RenderError("encoder", f"ffmpeg failed: {exc}", self.path) from exc
        os.replace(self._part, self.path)
        times = self._renderer.render_times_s or [0.0]
        return VideoStats(
            path=self.path,
            frames=self.frames,
            width=self.settings.width,
            height=self.settings.height,
            fps=self.settings.fps,
            t_first=self._t_first,
            t_last=self._t_last,
            backend=self._renderer.backend,
            render_ms_median=statistics.median(times) * 1e3,
            render_ms_mean=statistics.fmean(times) * 1e3,
            wall_s=time.perf_counter() - self._wall0,
        )

    def abort(self) -> None:
        """Stop without a video: free GL, stop ffmpeg, remove the partial file."""
        if self._closed:
            return
        self._closed = True
        self._renderer.close()
        if self._writer is not None:
            with contextlib.suppress(OSError, RuntimeError):
                self._writer.close()
        self._part.unlink(missing_ok=True)


def write_video(
    model: mujoco.MjModel,
    trunk_body: str,
    samples: Iterable[RenderSample],
    path: str | Path,
    settings: VideoSettings | None = None,
) -> VideoStats:
    """Render `samples` (time order) of the scene `model` into the MP4 `path`."""
    with VideoRecorder(model, trunk_body, path, settings) as recorder:
        recorder.add_all(samples)
        return recorder.close()


def expected_frames(t_last: float, fps: int = 30) -> int:
    """Frames of a video whose samples run from t = 0 to `t_last` (s), at `fps`."""
    n = 0
    while frame_time_ns(n, fps) <= round(t_last * 1e9):
        n += 1
    return n
