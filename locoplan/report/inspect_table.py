"""What ``locoplan inspect`` shows of a run's MCAP log, built from the log alone.

`inspect_renderables(log)` returns rich renderables (the CLI prints them; nothing here
prints): the run (file, status, scenario, strategy/model, duration, why it stopped), the
scenario's tasks (from the ``scenario.yaml`` attachment), the metrics table (when the run
finished) and the topics with their message counts and rates. Incomplete logs (writer killed)
and aborted runs say so.
"""

from __future__ import annotations

from typing import Any

from rich.console import RenderableType
from rich.table import Table
from rich.text import Text

from locoplan.exceptions import ScenarioError
from locoplan.log import topics
from locoplan.log.reader import RunLog
from locoplan.report.metrics_table import metrics_table

_RUN_KEYS = ("strategy", "model", "mapping", "qp_backend")
_MAX_DETAIL = 60  # characters of a task's parameters shown in the tasks table


def run_status(log: RunLog) -> str:
    """``finished``, ``aborted`` or ``closed`` as the writer recorded it, or ``incomplete``
    for a file without summary (its writer was killed)."""
    if not log.complete:
        return "incomplete"
    return log.metadata.get(topics.METADATA_RUN_END, {}).get("status") or "closed"


def stop_events(log: RunLog) -> list[tuple[float, dict[str, Any]]]:
    """The ``fall`` and ``aborted`` events of the log, in time order (empty without events)."""
    if topics.EVENTS not in log.topics:
        return []
    return [
        (t, msg)
        for t, msg in log.messages(topics.EVENTS)
        if isinstance(msg, dict) and msg.get("kind") in ("fall", "aborted")
    ]


def _duration(log: RunLog) -> float | None:
    if log.start_time is None or log.end_time is None:
        return None
    return log.end_time - log.start_time


def run_table(log: RunLog) -> Table:
    """The run's identity and how it ended."""
    table = Table(title="run", show_header=False, title_justify="left")
    table.add_column("field", style="bold")
    table.add_column("value")
    run = log.metadata.get(topics.METADATA_RUN, {})
    status = run_status(log)
    note = {
        "incomplete": " (the writer was killed: what follows is what survived)",
        "aborted": " (the run broke or was interrupted: no metrics)",
    }.get(status, "")
    table.add_row("file", str(log.path))
    table.add_row("status", Text(status + note, style="red" if note else "green"))
    table.add_row("scenario", run.get("scenario") or "-")
    for key in _RUN_KEYS:
        if key in run:
            table.add_row(key, run[key])
    table.add_row("locoplan", run.get("locoplan_version") or "-")
    table.add_row("started", run.get("start_wall_time") or "-")
    duration = _duration(log)
    table.add_row(
        "duration",
        "no messages"
        if duration is None
        else f"{duration:.3f} s of simulation (t = {log.start_time:.3f} .. {log.end_time:.3f} s)",
    )
    for t, msg in stop_events(log):
        detail = ", ".join(f"{k}={v}" for k, v in msg.items() if k != "kind")
        table.add_row(str(msg["kind"]), f"t = {t:.3f} s" + (f": {detail}" if detail else ""))
    return table


def tasks_table(log: RunLog) -> RenderableType:
    """The scenario's tasks as written (action, start, duration, parameters), or a line
    saying why they cannot be shown."""
    from locoplan.scenario import load_scenario_file

    text = log.scenario_text
    if text is None:
        return Text("scenario: not stored in this log", style="yellow")
    try:
        scenario = load_scenario_file(log.path.with_suffix(".yaml"), text).scenario
    except ScenarioError as exc:
        return Text(f"scenario stored but it does not load any more:\n{exc}", style="yellow")
    title = f"scenario {scenario.name}: {len(scenario.tasks)} tasks"
    if scenario.end is not None:
        title += f", end {scenario.end:g} s"
    table = Table(title=title, title_justify="left")
    for name, justify in (("#", "right"), ("action", "left"), ("start s", "right")):
        table.add_column(name, justify=justify)  # type: ignore[arg-type]
    table.add_column("duration s", justify="right")
    table.add_column("parameters")
    for i, task in enumerate(scenario.tasks):
        params = task.model_dump(exclude={"action", "start", "duration"}, exclude_none=True)
        detail = ", ".join(f"{k}: {v}" for k, v in params.items())
        if len(detail) > _MAX_DETAIL:
            detail = detail[: _MAX_DETAIL - 3] + "..."
        table.add_row(str(i), task.action, f"{task.start:g}", f"{task.duration:g}", detail)
    return table


def topics_table(log: RunLog) -> Table:
    """Every topic with its schema, message count and mean rate over the log's duration."""
    duration = _duration(log)
    total = sum(info.message_count for info in log.topics.values())
    table = Table(title=f"topics: {len(log.topics)}, {total} messages", title_justify="left")
    table.add_column("topic")
    table.add_column("schema")
    table.add_column("messages", justify="right")
    table.add_column("rate Hz", justify="right")
    for name, info in sorted(log.topics.items()):
        rate = (
            f"{info.message_count / duration:.1f}" if duration and info.message_count > 1 else "-"
        )
        table.add_row(name, info.schema_name or "-", str(info.message_count), rate)
    return table


def inspect_renderables(log: RunLog) -> list[RenderableType]:
    """Run, tasks, metrics (or why there are none) and topics, in that order."""
    out: list[RenderableType] = [run_table(log), tasks_table(log)]
    metrics = log.metrics
    if metrics is not None:
        try:
            out.append(metrics_table(metrics))
        except (KeyError, TypeError) as exc:
            out.append(Text(f"metrics stored but not in the expected form ({exc})", "yellow"))
    else:
        out.append(Text("metrics: none (the run did not finish)", style="yellow"))
    out.append(topics_table(log))
    return out
