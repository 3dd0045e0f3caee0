"""`locoplan batch` and `locoplan sweep`: many runs in worker processes (or Ray)."""

from __future__ import annotations

from typing import Any

import typer
from rich.console import Console

from locoplan.cli.common import (
    EXIT_BAD_INPUT,
    MAX_SIM_TIME,
    _fail,
    _interrupted,
    _load_with_text_or_exit,
    app,
    err,
    out,
)

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

_BACKEND = typer.Option(
    "local",
    "--backend",
    metavar="local|ray",
    help="local: worker processes on this machine; ray: Ray tasks, on a cluster or a local "
    "Ray (pip install 'locoplan\\[ray]').",
)
_ADDRESS = typer.Option(
    None,
    "--address",
    metavar="A",
    help="Ray cluster to use (ray://HOST:10001, HOST:6379 as printed by 'ray start --head', "
    "or 'auto' for the one running here); default: a local Ray started for this command "
    "with --jobs CPUs, stopped after.",
    show_default=False,
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


def _exit_if_interrupted(results: list[Any], out_dir: object) -> None:
    """After a batch or sweep whose workers a signal stopped (the summary printed): exit
    130 / 143 saying how many runs finished."""
    from locoplan import interrupt

    signum = interrupt.pending()
    if not signum:
        return
    statuses = [getattr(getattr(r, "outcome", r), "status", "") for r in results]
    done = sum(s in ("passed", "failed", "error") for s in statuses)
    _interrupted(
        interrupt.Interrupted(signum),
        f"{done} of {len(statuses)} runs finished; the logs so far are in {out_dir}",
    )


def _check_backend(backend: str, address: str | None) -> None:
    """Exit 2 (nothing run) for an unknown --backend, --address without --backend ray, Ray
    missing, or a cluster address that accepts no connection."""
    from locoplan.batch import BACKENDS, BackendUnavailable

    if backend not in BACKENDS:
        _fail(EXIT_BAD_INPUT, f"unknown --backend '{backend}'; allowed: {', '.join(BACKENDS)}")
    if address is not None and backend != "ray":
        _fail(EXIT_BAD_INPUT, "--address needs --backend ray")
    if backend == "ray":
        from locoplan.batch.ray_backend import check_reachable, import_ray

        try:
            import_ray()
            if address is not None:
                check_reachable(address)
        except BackendUnavailable as exc:
            _fail(EXIT_BAD_INPUT, str(exc))


@app.command("batch")
def batch_command(
    paths: list[str] = _BATCH_PATHS,
    jobs: int | None = _BATCH_JOBS,
    backend: str = _BACKEND,
    address: str | None = _ADDRESS,
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
    max_sim_time: float = MAX_SIM_TIME,
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

    --backend ray runs the scripts as Ray tasks instead, one CPU each, on
    the cluster at --address or on a local Ray started for the batch: the
    same validation, table, JUnit report, cache and exit status; a task
    whose worker dies, or that runs past --timeout (cancelled), is that
    script's error. On a cluster, give --out a folder every node mounts.

    Exit status: 0 every script passed, 1 any failed or errored, 2 a bad
    command line (no scripts found, a missing path, a bad option),
    130 interrupted (Ctrl-C), 143 terminated (SIGTERM): the running scripts
    stop at their next control tick (logs closed), the summary shows what
    finished.

    Examples:

      locoplan batch scenarios/ --junit report.xml

      locoplan batch scenarios/ more/*.yaml --jobs 4 --timeout 120 --no-cache

      locoplan batch scenarios/stand.yaml scenarios/step.yaml --fail-fast

      locoplan batch scenarios/ --backend ray --address auto --junit report.xml
    """
    import time
    from pathlib import Path

    from locoplan import interrupt
    from locoplan.batch import (
        CACHE_DIRNAME,
        BackendUnavailable,
        BatchInputError,
        batch_exit_code,
        default_workers,
        prepare_batch,
        run_batch,
        write_junit,
    )
    from locoplan.report.batch_table import batch_table

    _check_backend(backend, address)
    out_path = Path(out_dir)
    try:
        cases = prepare_batch(paths, out_path, use_cache=not no_cache, max_sim_time=max_sim_time)
    except BatchInputError as exc:
        _fail(EXIT_BAD_INPUT, str(exc))
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
                backend=backend,
                address=address,
            )
    except BackendUnavailable as exc:
        _fail(EXIT_BAD_INPUT, str(exc))
    except (KeyboardInterrupt, SystemExit) as exc:
        if debug or interrupt.interruption(exc) is None:
            raise
        _interrupted(exc, f"the logs written so far are in {out_dir}")
    _print_table(batch_table(results))
    elapsed = time.perf_counter() - started
    if backend == "ray":
        where = f"Ray ({'cluster at ' + address if address else 'a local Ray'})"
    else:
        where = f"{jobs or default_workers()} workers"
    err.print(f"{len(results)} scripts in {elapsed:.1f} s on {where}", markup=False)
    _exit_if_interrupted(results, out_dir)
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
    backend: str = _BACKEND,
    address: str | None = _ADDRESS,
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
    max_sim_time: float = MAX_SIM_TIME,
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
    valid point, Ray missing), 130 interrupted (Ctrl-C), 143 terminated
    (SIGTERM): running points stop at their next control tick, the table,
    CSV and plot show what finished.

    Examples:

      locoplan sweep scenarios/standing-load.yaml --set objects.block.mass=0:16:1

      locoplan sweep scenarios/package-transfer.yaml
      --set tasks.1.start=0.6,0.8,1.0 --set gait.period=0.3,0.4

      locoplan sweep scenarios/step.yaml --set gait.period=0.3,0.4
      --backend ray --address auto
    """
    from pathlib import Path

    from locoplan import interrupt
    from locoplan.batch import (
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
    from locoplan.report.batch_table import sweep_table
    from locoplan.report.sweep_plot import plot_sweep
    from locoplan.scenario.model import Scenario

    _check_backend(backend, address)
    if metric not in PLOTTABLE:
        _fail(EXIT_BAD_INPUT, f"unknown --metric '{metric}'; allowed: {', '.join(PLOTTABLE)}")
    try:
        axes = [parse_set(spec) for spec in sets]
    except SweepSpecError as exc:
        _fail(EXIT_BAD_INPUT, str(exc))
    scenario, text = _load_with_text_or_exit(file, max_sim_time)
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
    try:
        with _LiveProgress(len(job_list), f"sweep ({backend})") as progress:
            outcomes = run_sweep(job_list, backend, jobs, address, timeout or None, progress)
    except BackendUnavailable as exc:
        _fail(EXIT_BAD_INPUT, str(exc))
    except (KeyboardInterrupt, SystemExit) as exc:
        if debug or interrupt.interruption(exc) is None:
            raise
        _interrupted(exc, f"the logs written so far are in {out_path}")
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
    _exit_if_interrupted(list(outcomes.values()), out_path)
    raise typer.Exit(sweep_exit_code(points, outcomes))
