"""`locoplan validate` and `locoplan schema`: check task scripts, print their JSON Schema."""

from __future__ import annotations

import sys

import typer

from locoplan.cli.common import EXIT_BAD_INPUT, EXIT_OK, MAX_SIM_TIME, _fail, app, err, out

_VALIDATE_FILES = typer.Argument(
    ...,
    metavar="FILE",
    help="Task scripts to check (YAML); '-' reads one from standard input.",
    show_default=False,
)


@app.command("validate")
def validate_command(
    files: list[str] = _VALIDATE_FILES, max_sim_time: float = MAX_SIM_TIME
) -> None:
    """Check task scripts against the format; nothing is simulated.

    Prints 'ok   FILE (name, N tasks)' for a valid file,
    and 'FILE:LINE:COLUMN: message' for each problem of an invalid one.
    A script whose simulation would end after --max-sim-time (default one
    hour simulated) is refused, with the wall time it would take. Each valid
    script's plan is compiled, so that what the planner finds infeasible (a
    carry or place pose the robot cannot hold statically) is reported here too.
    Exit status 0 when every file is valid, 2 otherwise.

    Examples:

      locoplan validate scenarios/*.yaml

      cat my-task.yaml | locoplan validate -
    """
    from locoplan.exceptions import ScenarioError
    from locoplan.plan import PlanError
    from locoplan.plan.errors import InfeasiblePlanError, plan_error_message
    from locoplan.scenario import load_scenario_file
    from locoplan.scenario.limits import sim_time_issue
    from locoplan.scenario.source import MAX_BYTES
    from locoplan.sim.robot_plan import compile_robot_plan

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
        too_long = sim_time_issue(loaded, max_sim_time)
        if too_long is not None:
            all_ok = False
            out.print(str(too_long), markup=False, emoji=False, highlight=False)
            continue
        try:
            compile_robot_plan(loaded.scenario)
        except InfeasiblePlanError as exc:
            all_ok = False
            message = plan_error_message(exc, name, loaded.text)
            out.print(message, markup=False, emoji=False, highlight=False)
            continue
        except PlanError:
            pass  # what the format allows; `plan` and `run` say why it cannot be planned
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
