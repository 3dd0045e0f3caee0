"""`locoplan run`: one closed-loop run in MuJoCo."""

from __future__ import annotations

import typer

from locoplan.cli.common import (
    EXIT_BAD_INPUT,
    EXIT_EXPECTATION,
    EXIT_OK,
    EXIT_RUN_BROKE,
    LIVE_PACE,
    LIVE_PORT,
    LIVE_WAIT,
    MAX_SIM_TIME,
    PREPARING,
    _check_video_option,
    _fail,
    _interrupted,
    _load_with_text_or_exit,
    _sim_progress,
    app,
    err,
    out,
)

_RUN_FILE = typer.Argument(
    ..., metavar="FILE", help="Task script (YAML); '-' reads it from standard input."
)


@app.command("run")
def run_command(
    file: str = _RUN_FILE,
    out_dir: str = typer.Option("runs", "--out", metavar="DIR", help="Where the MCAP log goes."),
    metrics_json: str | None = typer.Option(
        None, "--metrics-json", metavar="PATH", help="Also write the metrics as JSON."
    ),
    strategy: str | None = typer.Option(
        None, "--strategy", metavar="S", help="dynamic | quasi-static (default: the script's)."
    ),
    model: str | None = typer.Option(
        None,
        "--model",
        metavar="M",
        help="external-force (paper's Model 2) | combined (Model 1) (default: the script's).",
    ),
    duration_scale: float = typer.Option(
        1.0, "--duration-scale", metavar="K", help="Stretch every task time and 'end' by K."
    ),
    quiet: bool = typer.Option(False, "--quiet", help="No progress bar and no table."),
    mapping: str = typer.Option(
        "wbc", "--mapping", help="Torque mapping: wbc (paper's WBC QP) | jacobian (baseline)."
    ),
    qp_backend: str = typer.Option(
        "daqp", "--qp", help="QP solver for MPC and WBC: daqp | proxsuite | piqp."
    ),
    f_min: float | None = typer.Option(
        None, "--f-min", metavar="N", help="Minimum vertical force per stance foot (default 10 N)."
    ),
    debug: bool = typer.Option(False, "--debug", help="Show Python tracebacks of failures."),
    video: str | None = typer.Option(
        None,
        "--video",
        metavar="PATH.mp4",
        help="Also render the run into an MP4 (headless, 30 fps; see 'locoplan render').",
        callback=lambda value: _check_video_option(value),
    ),
    live: bool = typer.Option(
        False,
        "--live",
        help="Serve the run to Foxglove while it goes (Foxglove WebSocket on "
        "ws://localhost:PORT, the log's topics), paced by --pace; the MCAP is still written.",
    ),
    port: int = LIVE_PORT,
    pace: float | None = LIVE_PACE,
    wait: float | None = LIVE_WAIT,
    max_sim_time: float = MAX_SIM_TIME,
) -> None:
    """Run one task script closed loop in MuJoCo (multi-contact MPC + WBC).

    Writes DIR/<name>.mcap (open it in Foxglove: robot, contacts, MPC forces, torques)
    and prints the metrics. Exit status: 0 every expectation held, 1 an expectation
    failed, 2 bad input, 3 the run broke (solver failure, simulator instability),
    130 interrupted (Ctrl-C, SIGINT), 143 terminated (SIGTERM). The log written so far
    stays readable in every case: a signal stops the run at the next control tick.

    Examples:

      locoplan run scenarios/walk-square.yaml

      locoplan run scenarios/pick-walk-drop.yaml --live   # then Foxglove: ws://localhost:8765

      locoplan run scenarios/package-transfer.yaml --strategy quasi-static --metrics-json qs.json

      locoplan run scenarios/turn.yaml --duration-scale 1.5 --out /tmp/runs --quiet
    """
    import json
    from pathlib import Path

    from locoplan import interrupt
    from locoplan.plan import STRATEGIES, PlanError
    from locoplan.plan.errors import plan_error_message
    from locoplan.scenario.model import Scenario

    if strategy is not None and strategy not in STRATEGIES:
        _fail(EXIT_BAD_INPUT, f"unknown --strategy '{strategy}'; allowed: {', '.join(STRATEGIES)}")
    if model is not None and model not in ("external-force", "combined"):
        _fail(EXIT_BAD_INPUT, f"unknown --model '{model}'; allowed: external-force, combined")
    if mapping not in ("wbc", "jacobian"):
        _fail(EXIT_BAD_INPUT, f"unknown --mapping '{mapping}'; allowed: wbc, jacobian")
    if qp_backend not in ("daqp", "proxsuite", "piqp"):
        _fail(EXIT_BAD_INPUT, f"unknown --qp '{qp_backend}'; allowed: daqp, proxsuite, piqp")
    if not duration_scale > 0:
        _fail(EXIT_BAD_INPUT, f"--duration-scale must be positive, got {duration_scale}")
    if pace is not None and not live:
        _fail(EXIT_BAD_INPUT, "--pace applies with --live only")
    if wait is not None and not live:
        _fail(EXIT_BAD_INPUT, "--wait applies with --live only")
    scenario, text = _load_with_text_or_exit(file, max_sim_time)
    assert isinstance(scenario, Scenario)
    show = not quiet and out.is_terminal
    log_hint = Path(out_dir) / f"{scenario.name}.mcap"
    # From here a signal only sets a flag: the run stops at its next control tick (or the next
    # stage of its preparation), so the log is closed whole and no compiled kernel sees it.
    try:
        with interrupt.deferring():
            from locoplan.exceptions import SimulationError, SolverFailure
            from locoplan.sim.live import live_view_options
            from locoplan.sim.run import RunOptions, run_scenario

            options = RunOptions(
                strategy=strategy,
                model=model,
                duration_scale=duration_scale,
                out_dir=Path(out_dir),
                mapping=mapping,
                qp_backend=qp_backend,
                f_min=f_min,
                video=None if video is None else Path(video),
                live=live_view_options(port, pace, wait) if live else None,
            )
            with _sim_progress(show) as bar:
                # Until the first simulated step: building the scene and the controller, which
                # on a machine's first run also compiles the numeric kernels (numba, about
                # 25 s, cached afterwards).
                task_id = bar.add_task(f"{scenario.name}: {PREPARING}", total=1.0)

                def on_progress(t: float, total: float) -> None:
                    bar.update(task_id, completed=t, total=total, description=scenario.name)

                if options.live is not None:
                    err.print(
                        f"live view: Foxglove > Open connection > Foxglove WebSocket > "
                        f"ws://localhost:{port} (layout: docs/foxglove-layout.json); the run "
                        f"starts when a client subscribes, at most {options.live.wait:g} s "
                        "after the server is up",
                        markup=False,
                    )
                result = run_scenario(scenario, text, options, on_progress)
        interrupt.check()  # a signal that came while the run was ending
    except PlanError as exc:
        _fail(EXIT_BAD_INPUT, plan_error_message(exc, file, text))
    except OSError as exc:
        if not live or exc.errno is not None:
            raise
        _fail(EXIT_BAD_INPUT, f"--live: {exc}")
    except (SolverFailure, SimulationError) as exc:
        if debug:
            raise
        _fail(EXIT_RUN_BROKE, f"run failed: {exc}\nthe log up to the failure is in {log_hint}")
    except (KeyboardInterrupt, SystemExit) as exc:
        if interrupt.interruption(exc) is None:
            raise
        _interrupted(exc, _log_note(log_hint))
    except SystemError as exc:
        # A compiled kernel that saw an interruption (a signal before the handlers were set).
        if interrupt.interruption(exc) is None:
            raise
        _interrupted(exc, _log_note(log_hint))
    from locoplan.report.metrics_table import metrics_table

    if metrics_json is not None:
        try:
            Path(metrics_json).write_text(json.dumps(result.metrics, indent=2) + "\n", "utf-8")
        except OSError as exc:
            _fail(EXIT_BAD_INPUT, f"cannot write {metrics_json}: {exc.strerror or exc}")
    if not quiet:
        for note in result.plan.notes:
            out.print(f"planner: {note}", markup=False, highlight=False)
        out.print(metrics_table(result.metrics))
    raise typer.Exit(EXIT_OK if result.passed else EXIT_EXPECTATION)


def _log_note(log: object) -> str:
    """Where the interrupted run's log is, or that it stopped before opening one."""
    from pathlib import Path

    assert isinstance(log, Path)
    if log.exists():
        return f"the log up to here is in {log}"
    return "stopped while preparing the run, before its log was opened"
