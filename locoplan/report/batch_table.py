"""Rich tables for many runs: a batch summary and a sweep summary (the CLI prints them)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rich.table import Table
from rich.text import Text

from locoplan.batch.batch import BatchResult
from locoplan.batch.sweep import SweepAxis, format_value

_STATUS_STYLE = {"passed": "green", "failed": "red", "error": "bold red", "skipped": "yellow"}


def _number(value: Any, digits: int = 2, unit: str = "") -> str:
    if value is None:
        return "-"
    return f"{value:.{digits}f}{unit}"


def _yes_no(value: Any) -> str:
    if value is None:
        return "-"
    return "yes" if value else "no"


def status_text(status: str, cached: bool = False) -> Text:
    """A status word in its colour, `(cached)` appended for a cache hit."""
    text = Text(status, style=_STATUS_STYLE.get(status, ""))
    if cached:
        text.append(" (cached)", style="dim")
    return text


def batch_counts(results: Sequence[BatchResult]) -> dict[str, int]:
    """How many results have each status (every status present, zeros included)."""
    counts = dict.fromkeys(_STATUS_STYLE, 0)
    for result in results:
        counts[result.outcome.status] = counts.get(result.outcome.status, 0) + 1
    return counts


def batch_table(results: Sequence[BatchResult]) -> Table:
    """One row per script: status (cached runs marked), completion time, peak torque ratio,
    fell, wall time and what went wrong (the failed expectations, or the error)."""
    counts = batch_counts(results)
    caption = ", ".join(f"{n} {s}" for s, n in counts.items() if n)
    cached = sum(r.outcome.cached for r in results)
    if cached:
        caption += f" ({cached} from the cache)"
    table = Table(title="locoplan batch", caption=caption, caption_justify="left")
    table.add_column("scenario", overflow="fold")
    table.add_column("status", no_wrap=True)
    table.add_column("completion", justify="right", no_wrap=True)
    table.add_column("peak torque", justify="right", no_wrap=True)
    table.add_column("fell", justify="center")
    table.add_column("wall", justify="right", no_wrap=True)
    table.add_column("failed expectations / error", overflow="fold")
    for result in results:
        outcome = result.outcome
        m: Mapping[str, Any] = outcome.metrics or {}
        failed = outcome.status == "failed"
        problem = "\n".join(outcome.failures) if failed else outcome.message
        # A bad file's message starts with its path, which the row already shows.
        problem = problem.removeprefix(f"{result.case.case_id}:")
        if outcome.cached:
            wall = "cached"
        elif outcome.wall_time > 0:
            wall = f"{outcome.wall_time:.1f} s"
        else:
            wall = "-"
        table.add_row(
            result.case.case_id,
            status_text(outcome.status, outcome.cached),
            _number(m.get("completion_time"), 2, " s"),
            _number(m.get("peak_torque_ratio"), 2),
            _yes_no(m.get("fell")),
            wall,
            Text(problem),
        )
    return table


def sweep_table(axes: Sequence[SweepAxis], rows: Sequence[Mapping[str, Any]], metric: str) -> Table:
    """One row per point: the set values, fell, passed, the chosen metric and any error."""
    table = Table(title="locoplan sweep")
    for axis in axes:
        table.add_column(axis.key, justify="right")
    table.add_column(metric, justify="right")
    table.add_column("fell", justify="center")
    table.add_column("passed", justify="center")
    table.add_column("error", overflow="fold")
    for row in rows:
        value = row.get(metric)
        shown = "-" if value is None else format_value(value)
        table.add_row(
            *(format_value(row[a.key]) for a in axes),
            shown,
            _yes_no(row.get("fell")),
            _yes_no(row.get("passed")),
            Text(str(row.get("error") or "")),
        )
    return table
