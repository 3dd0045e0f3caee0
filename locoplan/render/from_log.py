"""The video of a saved run, from its MCAP log alone (``locoplan render``), no re-simulation.

The scene is rebuilt from the scenario text stored in the log (objects and fixtures; the
robot named by the scenario), and every ``/sim/qpos`` sample is posed and rendered through the
same `VideoRecorder` as ``run --video``, so both give the same frames. A log whose writer
was killed is read up to its last complete chunk, and rendered up to there.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

from locoplan.exceptions import LocoplanError
from locoplan.log.reader import RunLog, read_log
from locoplan.render.errors import RenderError
from locoplan.render.samples import SAMPLE_TOPIC, RenderSample
from locoplan.render.video import VideoSettings, VideoStats, write_video
from locoplan.sim.scene import Scene


def scene_from_log(log: RunLog) -> Scene:
    """The MuJoCo scene of the run, from the scenario stored in `log`. RenderError when the
    log holds no scenario or it cannot be loaded any more."""
    from locoplan.robot.description import load_robot_description
    from locoplan.scenario import load_scenario_file
    from locoplan.sim.run import scene_for

    text = log.scenario_text
    if text is None:
        raise RenderError("log", "the log holds no scenario.yaml attachment", log.path)
    try:
        scenario = load_scenario_file(log.path.with_suffix(".yaml"), text).scenario
        return scene_for(scenario, load_robot_description(scenario.robot))
    except LocoplanError as exc:
        detail = f"cannot rebuild the scene from its scenario: {exc}"
        raise RenderError("scene", detail, log.path) from exc


def samples_from_log(log: RunLog) -> Iterator[RenderSample]:
    """The ``/sim/qpos`` samples of `log` in time order. RenderError when the topic is
    missing (a log written before locoplan logged it) or a payload is not a sample."""
    if SAMPLE_TOPIC not in log.topics:
        raise RenderError(
            "log",
            f"the log has no {SAMPLE_TOPIC} topic (written by an older locoplan?); "
            "run the scenario again to get a log that can be rendered",
            log.path,
        )
    for t, payload in log.messages(SAMPLE_TOPIC):
        try:
            yield RenderSample.from_payload(t, payload)
        except ValueError as exc:
            raise RenderError("log", str(exc), log.path) from exc


def render_log(
    log_path: str | Path, video_path: str | Path, settings: VideoSettings | None = None
) -> tuple[VideoStats, RunLog]:
    """Render the run logged at `log_path` into the MP4 `video_path`.

    Returns the video's stats and the log read (its `complete` says whether the writer
    closed it). Raises LogReadError for a file that is not an MCAP log, RenderError when
    the log cannot be rendered (no scenario, no samples, no OpenGL).
    """
    log = read_log(log_path)
    scene = scene_from_log(log)
    stats = write_video(
        scene.model, scene.robot.trunk_body, samples_from_log(log), video_path, settings
    )
    return stats, log
