"""`locoplan plan`: compile a task script and print its contact schedule."""

from __future__ import annotations

import typer

from locoplan.cli.common import EXIT_BAD_INPUT, _fail, _load_with_text_or_exit, app, err, out

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
    of each hand, the object-held intervals, what the planner changed in the
    script's timing and why (a turn hurried so that the trunk faces an object
    at its lift-off), a reference summary
    (final position and yaw, total time) and the static payload margins of
    each carry and place pose (reach, worst torque ratio, centre of mass,
    payload limit).
    Exit status 0, or 2 for a script that breaks the format or that the
    planner refuses (e.g. a load the robot cannot hold).

    Examples:

      locoplan plan scenarios/package-transfer.yaml

      locoplan plan scenarios/package-transfer.yaml --strategy quasi-static --plot qs.png

      locoplan plan scenarios/throw.yaml --json throw-plan.json
    """
    import json
    from pathlib import Path

    from locoplan.plan import STRATEGIES, PlanError
    from locoplan.plan.errors import plan_error_message
    from locoplan.plan.payload import payload_margins
    from locoplan.report.payload_table import payload_table
    from locoplan.report.plan_table import plan_table
    from locoplan.scenario.model import Scenario
    from locoplan.sim.robot_plan import compile_robot_plan

    if strategy is not None and strategy not in STRATEGIES:
        _fail(EXIT_BAD_INPUT, f"unknown --strategy '{strategy}'; allowed: {', '.join(STRATEGIES)}")
    scenario, text = _load_with_text_or_exit(file)
    assert isinstance(scenario, Scenario)
    try:
        plan = compile_robot_plan(scenario, strategy)
        margins = payload_margins(plan, scenario.robot)
    except PlanError as exc:
        _fail(EXIT_BAD_INPUT, plan_error_message(exc, file, text))
    out.print(plan_table(plan))
    for note in plan.notes:
        out.print(f"planner: {note}", markup=False, highlight=False)
    if margins:
        out.print(payload_table(margins))
    if json_path is not None:
        document = plan.to_dict()
        document["payload"] = [m.to_dict() for m in margins]
        try:
            Path(json_path).write_text(json.dumps(document, indent=1) + "\n", "utf-8")
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
