"""`locoplan compare`: one script run twice (quasi-static vs dynamic, or Model 1 vs 2)."""

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
    _fail,
    _interrupted,
    _load_with_text_or_exit,
    _sim_progress,
    app,
    err,
    out,
)

_COMPARE_FILE = typer.Argument(
    ..., metavar="FILE", help="Task script (YAML); '-' reads it from standard input."
)


@app.command("compare")
def compare_command(
    file: str = _COMPARE_FILE,
    out_dir: str | None = typer.Option(
        None,
        "--out",
        metavar="DIR",
        help="Where compare.json, both MCAP logs and the plots go "
        "(default runs/<name>-compare, or runs/<name>-models with --models).",
        show_default=False,
    ),
    models: bool = typer.Option(
        False,
        "--models",
        help="Compare the SRBD models external-force (Model 2) and combined (Model 1) "
        "instead of the strategies.",
    ),
    jobs: int | None = typer.Option(
        None,
        "--jobs",
        metavar="N",
        help="Runs at once in separate processes (default min(2, cores); 1 runs in this one).",
        show_default=False,
    ),
    strategy: str | None = typer.Option(
        None,
        "--strategy",
        metavar="S",
        help="With --models: the strategy of both runs (default: the script's).",
        show_default=False,
    ),
    qp_backend: str = typer.Option(
        "daqp", "--qp", help="QP solver for MPC and WBC: daqp | proxsuite | piqp."
    ),
    no_plots: bool = typer.Option(False, "--no-plots", help="Skip the PNG plots."),
    quiet: bool = typer.Option(False, "--quiet", help="No progress bars and no table."),
    debug: bool = typer.Option(False, "--debug", help="Show Python tracebacks of failures."),
    live: bool = typer.Option(
        False,
        "--live",
        help="Serve each run to Foxglove while it goes, one after the other (Foxglove "
        "WebSocket on ws://localhost:PORT; the client reconnects for the second run).",
    ),
    port: int = LIVE_PORT,
    pace: float | None = LIVE_PACE,
    wait: float | None = LIVE_WAIT,
    max_sim_time: float = MAX_SIM_TIME,
) -> None:
    """Run a task script twice and compare: quasi-static vs dynamic, or Model 1 vs 2.

    Without --models: the script under 'strategy: quasi-static' (tasks
    re-timed by the plan compiler so that locomotion and manipulation never
    overlap) and 'strategy: dynamic' (the written timing). With --models:
    'model: external-force' (the paper's Model 2) and 'model: combined'
    (Model 1), both on one strategy.

    Prints a side-by-side table with a difference column and writes to DIR:
    compare.json ({"quasi-static": metrics, "dynamic": metrics}, or
    {"external-force": ..., "combined": ...}), <name>-<label>.mcap per run,
    and the plots yaw.png (trunk yaw, pick and drop starts, yaw difference),
    contacts.png (contact timeline), torque-left-leg.png (leg joint torques
    against their limits), paths.png (top view of trunk and object paths)
    and pitch.png (trunk lean). When both strategies give the same schedule
    it says so and checks that the completion times agree within one MPC
    step.

    Exit status: 0 every expectation held in both runs, 1 an expectation
    failed in either, 2 bad input, 3 a run broke (its partial log is kept),
    130 interrupted (Ctrl-C), 143 terminated (SIGTERM): both runs stop at their
    next control tick and keep their logs.

    Examples:

      locoplan compare scenarios/package-transfer.yaml --out runs/pt

      locoplan compare scenarios/model-comparison.yaml --models

      locoplan compare scenarios/turn.yaml --jobs 1 --quiet

      locoplan compare scenarios/package-transfer.yaml --live
    """
    from pathlib import Path

    from rich.progress import TaskID

    from locoplan import interrupt
    from locoplan.compare import (
        CompareKind,
        compare_scenario,
        comparison_variants,
        write_compare_json,
    )
    from locoplan.plan import STRATEGIES, PlanError
    from locoplan.plan.errors import plan_error_message
    from locoplan.report.compare_plots import plot_comparison
    from locoplan.report.compare_table import compare_table
    from locoplan.scenario.model import Scenario

    if strategy is not None and not models:
        _fail(
            EXIT_BAD_INPUT, "--strategy applies with --models only (compare runs both strategies)"
        )
    if strategy is not None and strategy not in STRATEGIES:
        _fail(EXIT_BAD_INPUT, f"unknown --strategy '{strategy}'; allowed: {', '.join(STRATEGIES)}")
    if jobs is not None and jobs < 1:
        _fail(EXIT_BAD_INPUT, f"--jobs must be at least 1, got {jobs}")
    if qp_backend not in ("daqp", "proxsuite", "piqp"):
        _fail(EXIT_BAD_INPUT, f"unknown --qp '{qp_backend}'; allowed: daqp, proxsuite, piqp")
    if pace is not None and not live:
        _fail(EXIT_BAD_INPUT, "--pace applies with --live only")
    if wait is not None and not live:
        _fail(EXIT_BAD_INPUT, "--wait applies with --live only")
    scenario, text = _load_with_text_or_exit(file, max_sim_time)
    assert isinstance(scenario, Scenario)
    kind: CompareKind = "models" if models else "strategies"
    directory = Path(out_dir or f"runs/{scenario.name}-{'models' if models else 'compare'}")
    labels = [v.label for v in comparison_variants(scenario, kind, strategy)]
    show = not quiet and out.is_terminal
    live_view = None
    if live:
        from locoplan.sim.live import live_view_options

        live_view = live_view_options(port, pace, wait)
        err.print(
            f"live view: Foxglove > Open connection > Foxglove WebSocket > ws://localhost:{port}"
            f" ({' then '.join(labels)}; layout: docs/foxglove-layout.json); each run starts"
            f" when a client subscribes, at most {live_view.wait:g} s after its server is up",
            markup=False,
        )
    try:
        with interrupt.deferring(), _sim_progress(show, label_width=14) as bar:
            bars: dict[str, TaskID] = {label: bar.add_task(label, total=1.0) for label in labels}

            def on_progress(label: str, t: float, total: float) -> None:
                bar.update(bars[label], completed=t, total=total)

            comparison = compare_scenario(
                scenario,
                text,
                directory,
                kind=kind,
                strategy=strategy,
                jobs=jobs,
                qp_backend=qp_backend,
                progress=on_progress,
                live=live_view,
            )
        interrupt.check()
    except PlanError as exc:
        _fail(EXIT_BAD_INPUT, plan_error_message(exc, file, text))
    except OSError as exc:
        if live and exc.errno is None:  # the live server's port
            _fail(EXIT_BAD_INPUT, f"--live: {exc}")
        _fail(EXIT_BAD_INPUT, f"cannot write to {directory}: {exc.strerror or exc}")
    except (KeyboardInterrupt, SystemExit) as exc:
        if interrupt.interruption(exc) is None:
            raise
        _interrupted(exc, f"the logs up to here are in {directory}")
    try:
        write_compare_json(comparison, directory / "compare.json")
        plots = () if no_plots else plot_comparison(comparison)
    except OSError as exc:
        _fail(EXIT_BAD_INPUT, f"cannot write to {directory}: {exc.strerror or exc}")
    if not quiet:
        out.print(compare_table(comparison))
        if comparison.schedule_note:
            out.print(comparison.schedule_note, markup=False)
        logs = [o.log_path.name for o in comparison.outcomes if o.log_path is not None]
        written = ["compare.json", *logs, *(p.path.name for p in plots)]
        out.print(f"wrote {', '.join(written)} to {directory}", markup=False)
    for o in comparison.outcomes:
        if o.broke:
            err.print(
                f"{o.label} run failed: {o.error}\nits log up to the failure is in {o.log_path}",
                markup=False,
            )
    if comparison.broke:
        if debug:
            err.print("(no traceback: the failure happened in a worker run)", markup=False)
        raise typer.Exit(EXIT_RUN_BROKE)
    raise typer.Exit(EXIT_OK if comparison.passed else EXIT_EXPECTATION)
