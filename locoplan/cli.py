"""Command-line interface. The only module that imports typer; commands stay thin.

Exit codes (shared/cli-contract.md): 0 ok, 1 expectation failed, 2 bad input,
3 the run broke (solver failure, simulator instability), 130 interrupted.
"""

from __future__ import annotations

import sys
from typing import NoReturn

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from locoplan import __version__

EXIT_OK = 0
EXIT_EXPECTATION = 1
EXIT_BAD_INPUT = 2
EXIT_RUN_BROKE = 3
EXIT_INTERRUPTED = 130

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
    version: bool = typer.Option(False, "--version", help="Print the version and exit."),
) -> None:
    if version:
        out.print(f"locoplan {__version__}")
        raise typer.Exit(EXIT_OK)


# --- validate / schema (scenario) -------------------------------------------------------------


_VALIDATE_FILES = typer.Argument(
    ...,
    metavar="FILE",
    help="Task scripts to check (YAML); '-' reads one from standard input.",
    show_default=False,
)


@app.command("validate")
def validate_command(files: list[str] = _VALIDATE_FILES) -> None:
    """Check task scripts against the format; nothing is simulated.

    Prints 'ok   FILE (name, N tasks)' for a valid file,
    and 'FILE:LINE:COLUMN: message' for each problem of an invalid one.
    Exit status 0 when every file is valid, 2 otherwise.

    Examples:

      locoplan validate scenarios/*.yaml

      cat my-task.yaml | locoplan validate -
    """
    from locoplan.exceptions import ScenarioError
    from locoplan.scenario import load_scenario_file
    from locoplan.scenario.source import MAX_BYTES

    stdin_data: bytes | str | None = None
    all_ok = True
    for name in files:
        text: bytes | str | None = None
        if name == "-":
            if stdin_data is None:  # read once; a second '-' sees the same text
                buffer = getattr(sys.stdin, "buffer", None)
                stdin_data = buffer.read(MAX_BYTES + 1) if buffer else sys.stdin.read()
            text = stdin_data
        try:
            loaded = load_scenario_file(name, text)
        except ScenarioError as exc:
            all_ok = False
            for issue in exc.issues:
                out.print(str(issue), markup=False, emoji=False, highlight=False)
            continue
        n = len(loaded.scenario.tasks)
        shown = "<stdin>" if name == "-" else name
        summary = f"ok   {shown} ({loaded.scenario.name}, {n} task{'' if n == 1 else 's'})"
        out.print(summary, markup=False, emoji=False, highlight=False)
    raise typer.Exit(EXIT_OK if all_ok else EXIT_BAD_INPUT)


_SCHEMA_OUT = typer.Option(
    None,
    "--out",
    metavar="PATH",
    help="Write the schema to this file instead of standard output.",
    dir_okay=False,
)


@app.command("schema")
def schema_command(out_path: str | None = _SCHEMA_OUT) -> None:
    """Print the JSON Schema (draft 2020-12) of the task-script format.

    For editors (YAML language servers) and CI linters.
    Semantic rules (objects held before a drop, no overlapping locomotion)
    are checked by 'locoplan validate' only.

    Examples:

      locoplan schema > locoplan-task.schema.json

      locoplan schema --out .vscode/locoplan-task.schema.json
    """
    import json
    from pathlib import Path

    from locoplan.scenario import scenario_json_schema

    text = json.dumps(scenario_json_schema(), indent=2, ensure_ascii=False) + "\n"
    if out_path is None:
        out.print(text, end="", markup=False, emoji=False, highlight=False)
        return
    try:
        Path(out_path).write_text(text, encoding="utf-8")
    except OSError as exc:
        _fail(EXIT_BAD_INPUT, f"cannot write {out_path}: {exc.strerror or exc}")
    err.print(f"wrote {out_path}", markup=False, emoji=False, highlight=False)


# --- plan -----------------------------------------------------------------------------------

_PLAN_FILE = typer.Argument(
    ..., metavar="FILE", help="Task script (YAML); '-' reads it from standard input."
)
_PLAN_STRATEGY = typer.Option(
    None,
    "--strategy",
    metavar="S",
    help="dynamic | quasi-static (default: the script's own 'strategy').",
    show_default=False,
)
_PLAN_JSON = typer.Option(
    None, "--json", metavar="PATH", help="Also write the plan as JSON to PATH.", dir_okay=False
)
_PLAN_PLOT = typer.Option(
    None,
    "--plot",
    metavar="PATH.png",
    help="Also draw the schedule as a timeline (PNG) with the yaw reference.",
    dir_okay=False,
)


@app.command("plan")
def plan_command(
    file: str = _PLAN_FILE,
    strategy: str | None = _PLAN_STRATEGY,
    json_path: str | None = _PLAN_JSON,
    plot_path: str | None = _PLAN_PLOT,
) -> None:
    """Compile a task script and print its contact schedule; nothing is simulated.

    Prints the tasks with their planned start and end (re-timed for quasi-static),
    the stance/swing phases of each foot, the reach/grasp/carry/release phases
    of each hand, the object-held intervals and a reference summary
    (final position and yaw, total time).
    Exit status 0, or 2 for a script that breaks the format.

    Examples:

      locoplan plan scenarios/package-transfer.yaml

      locoplan plan scenarios/package-transfer.yaml --strategy quasi-static --plot qs.png

      locoplan plan scenarios/throw.yaml --json throw-plan.json
    """
    import json
    from pathlib import Path

    from locoplan.plan import STRATEGIES, PlanError, compile_plan
    from locoplan.report.plan_table import plan_table
    from locoplan.scenario.model import Scenario

    if strategy is not None and strategy not in STRATEGIES:
        _fail(EXIT_BAD_INPUT, f"unknown --strategy '{strategy}'; allowed: {', '.join(STRATEGIES)}")
    scenario, _ = _load_with_text_or_exit(file)
    assert isinstance(scenario, Scenario)
    try:
        plan = compile_plan(scenario, strategy)
    except PlanError as exc:
        shown = "<stdin>" if file == "-" else file
        _fail(EXIT_BAD_INPUT, f"{shown}: cannot plan: {exc}")
    out.print(plan_table(plan))
    if json_path is not None:
        try:
            Path(json_path).write_text(json.dumps(plan.to_dict(), indent=1) + "\n", "utf-8")
        except OSError as exc:
            _fail(EXIT_BAD_INPUT, f"cannot write {json_path}: {exc.strerror or exc}")
        err.print(f"wrote {json_path}", markup=False, emoji=False, highlight=False)
    if plot_path is not None:
        from locoplan.report.plan_plot import plot_plan

        try:
            plot_plan(plan, plot_path)
        except OSError as exc:
            _fail(EXIT_BAD_INPUT, f"cannot write {plot_path}: {exc.strerror or exc}")
        err.print(f"wrote {plot_path}", markup=False, emoji=False, highlight=False)


# --- run ------------------------------------------------------------------------------------

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
) -> None:
    """Run one task script closed loop in MuJoCo (multi-contact MPC + WBC).

    Writes DIR/<name>.mcap (open it in Foxglove: robot, contacts, MPC forces, torques)
    and prints the metrics. Exit status: 0 every expectation held, 1 an expectation
    failed, 2 bad input, 3 the run broke (solver failure, simulator instability),
    130 interrupted. The log written so far stays readable in every case.

    Examples:

      locoplan run scenarios/walk-square.yaml

      locoplan run scenarios/package-transfer.yaml --strategy quasi-static --metrics-json qs.json

      locoplan run scenarios/turn.yaml --duration-scale 1.5 --out /tmp/runs --quiet
    """
    import json
    from pathlib import Path

    from locoplan.exceptions import SimulationError, SolverFailure
    from locoplan.log.termination import install_termination_handlers
    from locoplan.plan import STRATEGIES, PlanError
    from locoplan.report.metrics_table import metrics_table
    from locoplan.scenario.model import Scenario
    from locoplan.sim.run import RunOptions, run_scenario

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
    scenario, text = _load_with_text_or_exit(file)
    assert isinstance(scenario, Scenario)
    options = RunOptions(
        strategy=strategy,
        model=model,
        duration_scale=duration_scale,
        out_dir=Path(out_dir),
        mapping=mapping,
        qp_backend=qp_backend,
        f_min=f_min,
        video=None if video is None else Path(video),
    )
    show = not quiet and out.is_terminal
    restore = install_termination_handlers()
    log_hint = Path(out_dir) / f"{scenario.name}.mcap"
    try:
        with _sim_progress(show) as bar:
            # Until the first simulated step: building the scene and the controller, which on
            # a machine's first run also compiles the numeric kernels (numba, about 25 s,
            # cached afterwards).
            task_id = bar.add_task(f"{scenario.name}: {PREPARING}", total=1.0)

            def on_progress(t: float, total: float) -> None:
                bar.update(task_id, completed=t, total=total, description=scenario.name)

            result = run_scenario(scenario, text, options, on_progress)
    except PlanError as exc:
        _fail(EXIT_BAD_INPUT, f"{file}: cannot plan: {exc}")
    except (SolverFailure, SimulationError) as exc:
        if debug:
            raise
        _fail(EXIT_RUN_BROKE, f"run failed: {exc}\nthe log up to the failure is in {log_hint}")
    except (KeyboardInterrupt, SystemExit) as exc:
        if isinstance(exc, SystemExit) and exc.code in (0, None):
            raise
        _fail(EXIT_INTERRUPTED, f"interrupted; the log up to here is in {log_hint}")
    finally:
        restore()
    if metrics_json is not None:
        try:
            Path(metrics_json).write_text(json.dumps(result.metrics, indent=2) + "\n", "utf-8")
        except OSError as exc:
            _fail(EXIT_BAD_INPUT, f"cannot write {metrics_json}: {exc.strerror or exc}")
    if not quiet:
        out.print(metrics_table(result.metrics))
    raise typer.Exit(EXIT_OK if result.passed else EXIT_EXPECTATION)


def _load_with_text_or_exit(name: str) -> tuple[object, str]:
    """Load a task script and its text; on bad input print every issue and exit 2."""
    from locoplan.exceptions import ScenarioError
    from locoplan.scenario import load_scenario_file
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
    return loaded.scenario, loaded.text


# --- batch / sweep --------------------------------------------------------------------------

_BATCH_PATHS = typer.Argument(
    ...,
    metavar="PATH...",
    help="Task scripts, or directories searched recursively for *.yaml / *.yml.",
    show_default=False,
)
_BATCH_JOBS = typer.Option(
    None,
    "--jobs",
    "-j",
    metavar="N",
    min=1,
    help="Worker processes running at once (default: one per core).",
    show_default=False,
)
_BATCH_TIMEOUT = typer.Option(
    600.0,
    "--timeout",
    metavar="S",
    min=0.0,
    help="Stop a run whose worker takes longer than S seconds (wall time) and count it as "
    "an error; 0 for no limit.",
)

_SWEEP_SETS = typer.Option(
    ...,
    "--set",
    metavar="KEY=VALUES",
    help="A dotted key of the script and its values: START:STOP:STEP (inclusive) or a "
    "comma list; list items by 0-based index (tasks.1.start). Repeat for a grid.",
    show_default=False,
)


class _LiveProgress:
    """Progress of many runs (a `RunListener`): on a terminal, an overall bar and one bar per
    running job in simulated seconds; elsewhere (CI logs), one line per finished run."""

    def __init__(self, total: int, label: str) -> None:
        from rich.progress import (
            BarColumn,
            Progress,
            TaskID,
            TextColumn,
            TimeElapsedColumn,
        )

        self.live = out.is_terminal
        self.done = 0
        self.total = total
        self.tasks: dict[str, TaskID] = {}
        self.bar = Progress(
            TextColumn("[bold]{task.description}", table_column=None),
            BarColumn(),
            TextColumn("{task.fields[note]}"),
            TimeElapsedColumn(),
            console=out,
            disable=not self.live,
            transient=True,
        )
        self.overall = self.bar.add_task(label, total=total, note=f"0/{total}")

    def __enter__(self) -> _LiveProgress:
        self.bar.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        self.bar.__exit__(None, None, None)

    def started(self, job: object) -> None:
        from locoplan.batch import Job

        assert isinstance(job, Job)
        if self.live:
            self.tasks[job.job_id] = self.bar.add_task(f"  {job.job_id}", total=None, note="")

    def progress(self, job: object, t: float, total: float) -> None:
        from locoplan.batch import Job

        assert isinstance(job, Job)
        task = self.tasks.get(job.job_id)
        if task is not None:
            note = f"t = {t:.1f} / {total:.1f} s"
            self.bar.update(task, total=total, completed=t, note=note)

    def finished(self, outcome: object) -> None:
        from locoplan.batch import Outcome

        assert isinstance(outcome, Outcome)
        self.done += 1
        task = self.tasks.pop(outcome.job_id, None)
        if task is not None:
            self.bar.remove_task(task)
        self.bar.update(self.overall, completed=self.done, note=f"{self.done}/{self.total}")
        how = "cached" if outcome.cached else f"{outcome.wall_time:.1f} s"
        line = f"[{self.done}/{self.total}] {outcome.status:<7} {outcome.job_id} ({how})"
        if outcome.status != "passed" and outcome.message:
            line += f": {outcome.message}"
        if self.live:
            self.bar.console.print(line, markup=False, emoji=False, highlight=False)
        else:
            err.print(line, markup=False, emoji=False, highlight=False)


def _print_table(table: object) -> None:
    """Print a wide table: a terminal's own width, else (CI logs, files) 160 columns instead
    of rich's 80, which would fold every cell."""
    if out.is_terminal:
        out.print(table)
    else:
        Console(file=out.file, width=160, highlight=False, soft_wrap=True).print(table)


@app.command("batch")
def batch_command(
    paths: list[str] = _BATCH_PATHS,
    jobs: int | None = _BATCH_JOBS,
    junit: str | None = typer.Option(
        None,
        "--junit",
        metavar="PATH",
        help="Also write a JUnit XML report (for CI).",
        dir_okay=False,
    ),
    out_dir: str = typer.Option(
        "runs/batch",
        "--out",
        metavar="DIR",
        help="Where each run's MCAP log and metrics JSON go (the scripts' folders mirrored).",
    ),
    fail_fast: bool = typer.Option(
        False,
        "--fail-fast",
        help="Stop at the first script that fails or errs; the rest are reported as skipped.",
    ),
    timeout: float = _BATCH_TIMEOUT,
    no_cache: bool = typer.Option(
        False, "--no-cache", help="Run every script, even those with a cached result."
    ),
    debug: bool = typer.Option(False, "--debug", help="Show Python tracebacks of failures."),
) -> None:
    """Validate and run many task scripts in parallel (CI).

    Finds the scripts (files, or *.yaml / *.yml under directories,
    recursively) and validates all of them first: a bad file is an error
    naming FILE:LINE:COLUMN, nothing simulated. Then runs the valid ones
    closed loop, each in its own worker process: a worker that crashes, or
    runs past --timeout, is that script's error and the others go on.
    Prints a summary table (status, completion time, peak torque ratio,
    fell, wall time, failed expectations) and writes DIR/<script>.mcap and
    DIR/<script>.json for each run.

    Cache: a script whose text, locoplan's code (source and robot files,
    library versions) and run options are unchanged since a run into the
    same DIR is not simulated again; its stored metrics are reported and
    marked 'cached' (entries in DIR/.cache; --no-cache runs everything).

    Exit status: 0 every script passed, 1 any failed or errored, 2 a bad
    command line (no scripts found, a missing path, a bad option),
    130 interrupted.

    Examples:

      locoplan batch scenarios/ --junit report.xml

      locoplan batch scenarios/ more/*.yaml --jobs 4 --timeout 120 --no-cache

      locoplan batch scenarios/stand.yaml scenarios/step.yaml --fail-fast
    """
    import time
    from pathlib import Path

    from locoplan.batch import (
        CACHE_DIRNAME,
        BatchInputError,
        batch_exit_code,
        default_workers,
        prepare_batch,
        run_batch,
        write_junit,
    )
    from locoplan.log.termination import install_termination_handlers
    from locoplan.report.batch_table import batch_table

    out_path = Path(out_dir)
    try:
        cases = prepare_batch(paths, out_path, use_cache=not no_cache)
    except BatchInputError as exc:
        _fail(EXIT_BAD_INPUT, str(exc))
    restore = install_termination_handlers()
    started = time.perf_counter()
    try:
        with _LiveProgress(len(cases), "batch") as progress:
            results = run_batch(
                cases,
                workers=jobs,
                timeout=timeout or None,
                cache_dir=None if no_cache else out_path / CACHE_DIRNAME,
                listener=progress,
                fail_fast=fail_fast,
            )
    except (KeyboardInterrupt, SystemExit) as exc:
        if debug or (isinstance(exc, SystemExit) and exc.code in (0, None)):
            raise
        _fail(EXIT_INTERRUPTED, f"interrupted; the logs written so far are in {out_dir}")
    finally:
        restore()
    _print_table(batch_table(results))
    workers = jobs or default_workers()
    elapsed = time.perf_counter() - started
    err.print(f"{len(results)} scripts in {elapsed:.1f} s on {workers} workers", markup=False)
    if junit is not None:
        try:
            write_junit(results, Path(junit))
        except OSError as exc:
            _fail(EXIT_BAD_INPUT, f"cannot write {junit}: {exc.strerror or exc}")
        err.print(f"wrote {junit}", markup=False, emoji=False, highlight=False)
    raise typer.Exit(batch_exit_code(results))


@app.command("sweep")
def sweep_command(
    file: str = typer.Argument(..., metavar="FILE", help="The task script to sweep (YAML)."),
    sets: list[str] = _SWEEP_SETS,
    jobs: int | None = _BATCH_JOBS,
    backend: str = typer.Option(
        "local",
        "--backend",
        metavar="local|ray",
        help="local: worker processes on this machine; ray: Ray tasks (pip install "
        "'locoplan\\[ray]').",
    ),
    address: str | None = typer.Option(
        None,
        "--address",
        metavar="A",
        help="Ray cluster to use (as printed by 'ray start --head'; 'auto' finds a local "
        "one); default: a local Ray started for this sweep with --jobs CPUs.",
    ),
    out_dir: str | None = typer.Option(
        None,
        "--out",
        metavar="DIR",
        help="Where the CSV, the plot and each point's MCAP and metrics JSON go "
        "(default runs/sweep/<name>).",
        show_default=False,
    ),
    metric: str = typer.Option(
        "peak_torque_ratio",
        "--metric",
        metavar="NAME",
        help="Metric to plot: peak_torque_ratio, completion_time, yaw_difference_deg, "
        "real_time_factor, fell, completed or passed.",
    ),
    timeout: float = _BATCH_TIMEOUT,
    debug: bool = typer.Option(False, "--debug", help="Show Python tracebacks of failures."),
) -> None:
    """Run a task script over a grid of parameter values (payload, timing).

    Every point is the script with the --set values written in, validated
    as a script (an invalid point is reported with its key, value and
    FILE:LINE:COLUMN, and not run), then run closed loop in a worker.

    Writes DIR/<name>-sweep.csv, one row per point sorted by value: the set
    values, then fell, completed, completion_time, peak_torque_ratio,
    yaw_difference_deg, passed, real_time_factor, error. The CSV is the
    same on either backend, but for real_time_factor (a wall-time figure).
    Writes DIR/<name>-sweep.png: --metric over one key, or a heat map over
    two, with falls, failed expectations and unfinished tasks marked.

    Exit status: 0 every point passed, 1 some point failed, errored or was
    invalid, 2 a bad command line (bad --set, list index out of range, no
    valid point, Ray missing), 130 interrupted.

    Examples:

      locoplan sweep scenarios/standing-load.yaml --set objects.block.mass=0:16:1

      locoplan sweep scenarios/package-transfer.yaml
      --set tasks.1.start=0.6,0.8,1.0 --set gait.period=0.3,0.4

      locoplan sweep scenarios/step.yaml --set gait.period=0.3,0.4
      --backend ray --address auto
    """
    from pathlib import Path

    from locoplan.batch import (
        BACKENDS,
        PLOTTABLE,
        BackendUnavailable,
        SweepSpecError,
        build_points,
        csv_text,
        parse_set,
        run_sweep,
        sweep_exit_code,
        sweep_jobs,
        sweep_rows,
    )
    from locoplan.log.termination import install_termination_handlers
    from locoplan.report.batch_table import sweep_table
    from locoplan.report.sweep_plot import plot_sweep
    from locoplan.scenario.model import Scenario

    if backend not in BACKENDS:
        _fail(EXIT_BAD_INPUT, f"unknown --backend '{backend}'; allowed: {', '.join(BACKENDS)}")
    if metric not in PLOTTABLE:
        _fail(EXIT_BAD_INPUT, f"unknown --metric '{metric}'; allowed: {', '.join(PLOTTABLE)}")
    if address is not None and backend != "ray":
        _fail(EXIT_BAD_INPUT, "--address needs --backend ray")
    if backend == "ray":
        from locoplan.batch.ray_backend import import_ray

        try:
            import_ray()
        except BackendUnavailable as exc:
            _fail(EXIT_BAD_INPUT, str(exc))
    try:
        axes = [parse_set(spec) for spec in sets]
    except SweepSpecError as exc:
        _fail(EXIT_BAD_INPUT, str(exc))
    scenario, text = _load_with_text_or_exit(file)
    assert isinstance(scenario, Scenario)
    try:
        points = build_points(file, text, axes)
    except SweepSpecError as exc:
        _fail(EXIT_BAD_INPUT, str(exc))
    for point in points:
        if point.error is not None:
            err.print(f"invalid point {point.error}", markup=False, emoji=False, highlight=False)
    out_path = Path(out_dir) if out_dir is not None else Path("runs") / "sweep" / scenario.name
    job_list = sweep_jobs(points, axes, scenario.name, file, out_path)
    if not job_list:
        _fail(EXIT_BAD_INPUT, f"no valid point among {len(points)}; nothing run")
    restore = install_termination_handlers()
    try:
        with _LiveProgress(len(job_list), f"sweep ({backend})") as progress:
            outcomes = run_sweep(job_list, backend, jobs, address, timeout or None, progress)
    except BackendUnavailable as exc:
        _fail(EXIT_BAD_INPUT, str(exc))
    except (KeyboardInterrupt, SystemExit) as exc:
        if debug or (isinstance(exc, SystemExit) and exc.code in (0, None)):
            raise
        _fail(EXIT_INTERRUPTED, f"interrupted; the logs written so far are in {out_path}")
    finally:
        restore()
    rows = sweep_rows(axes, points, outcomes)
    _print_table(sweep_table(axes, rows, metric))
    csv_path = out_path / f"{scenario.name}-sweep.csv"
    png_path = out_path / f"{scenario.name}-sweep.png"
    try:
        out_path.mkdir(parents=True, exist_ok=True)
        csv_path.write_text(csv_text(axes, rows), encoding="utf-8")
        plot_sweep(rows, [a.key for a in axes], metric, png_path, title=f"{scenario.name} sweep")
    except OSError as exc:
        _fail(EXIT_BAD_INPUT, f"cannot write to {out_path}: {exc.strerror or exc}")
    err.print(f"wrote {csv_path}\nwrote {png_path}", markup=False, emoji=False, highlight=False)
    raise typer.Exit(sweep_exit_code(points, outcomes))


# --- compare --------------------------------------------------------------------------------

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
    130 interrupted.

    Examples:

      locoplan compare scenarios/package-transfer.yaml --out runs/pt

      locoplan compare scenarios/model-comparison.yaml --models

      locoplan compare scenarios/turn.yaml --jobs 1 --quiet
    """
    from pathlib import Path

    from rich.progress import TaskID

    from locoplan.compare import (
        CompareKind,
        compare_scenario,
        comparison_variants,
        write_compare_json,
    )
    from locoplan.log.termination import install_termination_handlers
    from locoplan.plan import STRATEGIES, PlanError
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
    scenario, text = _load_with_text_or_exit(file)
    assert isinstance(scenario, Scenario)
    kind: CompareKind = "models" if models else "strategies"
    directory = Path(out_dir or f"runs/{scenario.name}-{'models' if models else 'compare'}")
    labels = [v.label for v in comparison_variants(scenario, kind, strategy)]
    show = not quiet and out.is_terminal
    restore = install_termination_handlers()
    try:
        with _sim_progress(show, label_width=14) as bar:
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
            )
    except PlanError as exc:
        _fail(EXIT_BAD_INPUT, f"{file}: cannot plan: {exc}")
    except OSError as exc:
        _fail(EXIT_BAD_INPUT, f"cannot write to {directory}: {exc.strerror or exc}")
    except (KeyboardInterrupt, SystemExit) as exc:
        if isinstance(exc, SystemExit) and exc.code in (0, None):
            raise
        _fail(EXIT_INTERRUPTED, f"interrupted; the logs up to here are in {directory}")
    finally:
        restore()
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


# --- render / inspect -----------------------------------------------------------------------


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


def main() -> None:
    """Console-script entry point."""
    try:
        app()
    except KeyboardInterrupt:
        err.print("interrupted", markup=False)
        sys.exit(EXIT_INTERRUPTED)
    except Exception as exc:
        # Bugs end here: say what broke without a traceback unless --debug asked for one.
        if "--debug" in sys.argv:
            raise
        err.print(
            f"internal error: {type(exc).__name__}: {exc} (rerun with --debug for the traceback)",
            markup=False,
        )
        sys.exit(EXIT_RUN_BROKE)


if __name__ == "__main__":
    main()
