"""`locoplan render` and `locoplan inspect`: a saved run's MCAP log as a video or tables."""

from __future__ import annotations

import typer

from locoplan.cli.common import EXIT_BAD_INPUT, _check_video_option, _fail, app, err, out


def _read_log_or_exit(path: str) -> object:
    """`read_log(path)`, or exit 2 saying why the file is not a readable log."""
    from locoplan.log.reader import LogReadError, read_log

    try:
        return read_log(path)
    except FileNotFoundError:
        _fail(EXIT_BAD_INPUT, f"{path}: no such file")
    except IsADirectoryError:
        _fail(EXIT_BAD_INPUT, f"{path}: is a directory, not an MCAP log")
    except LogReadError as exc:
        _fail(EXIT_BAD_INPUT, str(exc))
    except OSError as exc:
        _fail(EXIT_BAD_INPUT, f"{path}: cannot read: {exc.strerror or exc}")


_LOG_FILE = typer.Argument(..., metavar="LOG.mcap", help="A run's MCAP log (locoplan run).")


@app.command("render")
def render_command(
    log_path: str = _LOG_FILE,
    video: str = typer.Option(
        ..., "--video", metavar="PATH.mp4", help="Where to write the MP4.", show_default=False
    ),
    debug: bool = typer.Option(False, "--debug", help="Show Python tracebacks of failures."),
) -> None:
    """Render a saved run into an MP4, from its log alone (no re-simulation).

    The scene is rebuilt from the scenario stored in the log and posed from the
    logged states (/sim/qpos) at 30 fps, 640x480, with the same camera and overlay
    as 'locoplan run --video', so both give the same frames. A log cut short
    (the run broke, or its process was killed) is rendered up to where it ends.
    Needs software OpenGL: Mesa EGL (Debian: libegl1 libegl-mesa0 libgl1-mesa-dri),
    or MUJOCO_GL=osmesa with libosmesa6.
    Exit status 0, or 2 when the file is not a renderable locoplan log or
    rendering is not possible here.

    Examples:

      locoplan render runs/pick-walk-drop.mcap --video pick-walk-drop.mp4

      MUJOCO_GL=osmesa locoplan render runs/turn.mcap --video turn.mp4
    """
    from locoplan.log.reader import RunLog
    from locoplan.render.errors import RenderError
    from locoplan.render.from_log import render_log

    _check_video_option(video)
    log = _read_log_or_exit(log_path)
    assert isinstance(log, RunLog)
    try:
        stats, _ = render_log(log.path, video)
    except RenderError as exc:
        if debug:
            raise
        _fail(EXIT_BAD_INPUT, f"cannot render: {exc}")
    span = "" if stats.t_last is None else f", t = 0 .. {stats.t_last:.2f} s"
    note = "" if log.complete else " (the log is incomplete: rendered up to its end)"
    err.print(
        f"wrote {video}: {stats.frames} frame{'' if stats.frames == 1 else 's'} "
        f"{stats.width}x{stats.height} at {stats.fps} fps"
        f"{span}{note}; {stats.render_ms_median:.1f} ms per frame ({stats.backend})",
        markup=False,
    )


@app.command("inspect")
def inspect_command(
    log_path: str = _LOG_FILE,
    as_json: bool = typer.Option(
        False, "--json", help="Print the log summary as JSON instead of tables."
    ),
) -> None:
    """Show what a run's MCAP log holds: scenario, metrics, topics and duration.

    Reads the log alone (the scenario and metrics are stored in it). Works on logs
    of runs that broke or were killed, and says so.
    Exit status 0, or 2 when the file is not an MCAP log.

    Examples:

      locoplan inspect runs/package-transfer.mcap

      locoplan inspect runs/throw.mcap --json | jq .metrics.passed
    """
    import json

    from locoplan.log.reader import RunLog, log_summary
    from locoplan.report.inspect_table import inspect_renderables

    log = _read_log_or_exit(log_path)
    assert isinstance(log, RunLog)
    if as_json:
        out.print(json.dumps(log_summary(log.path), indent=2), markup=False, highlight=False)
        return
    for item in inspect_renderables(log):
        out.print(item)
