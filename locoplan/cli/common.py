"""Shared by every command: the typer `app`, the consoles, exit codes and small helpers.

Exit codes (shared/cli-contract.md): 0 ok, 1 expectation failed, 2 bad input,
3 the run broke (solver failure, simulator instability), 130 interrupted (SIGINT),
143 terminated (SIGTERM).

Signals: every command runs with `locoplan.interrupt`'s handlers (installed by the root
callback): SIGINT / SIGTERM stop it with `Interrupted` at once, except inside the commands'
`deferring()` blocks (simulations, batch parents), where they only set a flag the work checks
between control ticks.
"""

from __future__ import annotations

import sys
from typing import Any, NoReturn

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from locoplan import __version__

EXIT_OK = 0
EXIT_EXPECTATION = 1
EXIT_BAD_INPUT = 2
EXIT_RUN_BROKE = 3
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143  # SIGTERM (128 + 15, the shell's convention)

app = typer.Typer(
    name="locoplan",
    help=(
        "Plan and simulate humanoid loco-manipulation task scripts "
        "(multi-contact MPC + whole-body control in MuJoCo).\n\n"
        "Examples:\n\n"
        "  locoplan validate scenarios/*.yaml\n\n"
        "  locoplan plan scenarios/package-transfer.yaml --plot plan.png\n\n"
        "  locoplan run scenarios/package-transfer.yaml --metrics-json m.json"
    ),
    no_args_is_help=True,
    add_completion=False,
    rich_markup_mode="rich",
    pretty_exceptions_enable=False,
)

out = Console(highlight=False, soft_wrap=True)
err = Console(stderr=True, highlight=False, soft_wrap=True)


PREPARING = "preparing (a first run on this machine compiles kernels, ~25 s)"


def _sim_progress(show: bool, label_width: int = 0) -> Progress:
    """A progress display in simulated seconds (one bar per run); silent unless `show`."""
    width = f":<{label_width}" if label_width else ""
    return Progress(
        TextColumn("[bold]{task.description" + width + "}"),
        BarColumn(),
        TextColumn("t = {task.completed:.2f} / {task.total:.2f} s"),
        TimeElapsedColumn(),
        console=out,
        disable=not show,
        transient=True,
    )


def _fail(code: int, message: str) -> NoReturn:
    err.print(message, markup=False)
    raise typer.Exit(code)


@app.callback(invoke_without_command=True)
def _root(
    ctx: typer.Context,
    version: bool = typer.Option(False, "--version", help="Print the version and exit."),
) -> None:
    import threading

    from locoplan import interrupt

    if threading.current_thread() is threading.main_thread():
        ctx.call_on_close(interrupt.install(announce=True))
    if version:
        out.print(f"locoplan {__version__}")
        raise typer.Exit(EXIT_OK)


def _max_sim_time_option() -> Any:
    from locoplan.scenario.limits import DEFAULT_MAX_SIM_TIME

    return typer.Option(
        DEFAULT_MAX_SIM_TIME,
        "--max-sim-time",
        metavar="SECONDS",
        min=0.0,
        help="Refuse (exit 2) a script whose simulation would end later than this; the "
        "message estimates the wall time it would take.",
    )


MAX_SIM_TIME = _max_sim_time_option()
# The live view's port and pace, shared by `run` and `compare`.
LIVE_PORT = typer.Option(
    8765, "--port", metavar="PORT", min=0, max=65535, help="With --live: the port."
)
LIVE_PACE = typer.Option(
    None,
    "--pace",
    metavar="K",
    min=0.0,
    help="With --live: run at K times real time (default 1; 0: as fast as it goes).",
    show_default=False,
)
LIVE_WAIT = typer.Option(
    None,
    "--wait",
    metavar="SECONDS",
    min=0.0,
    help="With --live: start each run when a client subscribes to a topic, or after "
    "SECONDS without one (default 30; 0: start at once).",
    show_default=False,
)


def _interrupted(exc: BaseException, message: str) -> NoReturn:
    """Exit 130 (SIGINT, Ctrl-C) or 143 (SIGTERM) for an interruption, saying `message`
    after what stopped the command."""
    from locoplan import interrupt

    code = interrupt.interruption(exc) or EXIT_INTERRUPTED
    what = "terminated (SIGTERM)" if code == EXIT_TERMINATED else "interrupted"
    _fail(code, f"{what}; {message}" if message else what)


def _load_with_text_or_exit(name: str, max_sim_time: float | None = None) -> tuple[object, str]:
    """Load a task script and its text; on bad input (or, with `max_sim_time`, a script
    asking for more simulated time) print every issue and exit 2."""
    from locoplan.exceptions import ScenarioError
    from locoplan.scenario import load_scenario_file
    from locoplan.scenario.limits import sim_time_issue
    from locoplan.scenario.source import MAX_BYTES

    data: bytes | str | None = None
    if name == "-":
        buffer = getattr(sys.stdin, "buffer", None)
        data = buffer.read(MAX_BYTES + 1) if buffer else sys.stdin.read()
    try:
        loaded = load_scenario_file(name, data)
    except ScenarioError as exc:
        for issue in exc.issues:
            err.print(str(issue), markup=False, emoji=False, highlight=False)
        raise typer.Exit(EXIT_BAD_INPUT) from None
    too_long = None if max_sim_time is None else sim_time_issue(loaded, max_sim_time)
    if too_long is not None:
        err.print(str(too_long), markup=False, emoji=False, highlight=False)
        raise typer.Exit(EXIT_BAD_INPUT)
    return loaded.scenario, loaded.text


def _check_video_option(value: str | None) -> str | None:
    """Fail fast (exit 2, before any simulation) when a video cannot be written to `value`:
    not an .mp4 path, no encoder, or no OpenGL (a tiny context is opened to find out)."""
    if value is None:
        return None
    from pathlib import Path

    from locoplan.render.errors import RenderError
    from locoplan.render.gl import check_gl

    path = Path(value)
    if path.suffix.lower() != ".mp4":
        _fail(EXIT_BAD_INPUT, f"--video needs a .mp4 path, got {value}")
    if path.is_dir():
        _fail(EXIT_BAD_INPUT, f"--video {value} is a directory")
    try:
        import imageio_ffmpeg  # noqa: F401  (the encoder the video needs)

        check_gl()
    except ImportError:
        _fail(EXIT_BAD_INPUT, "the video encoder is missing: pip install 'imageio-ffmpeg~=0.8'")
    except RenderError as exc:
        _fail(EXIT_BAD_INPUT, str(exc))
    return value
