"""How much simulated time a script may ask for before it is refused.

A script whose simulation would end after `DEFAULT_MAX_SIM_TIME` (one hour simulated: some
20 minutes of wall time) is most likely a typo (`end: 1.0e9`) and would hold a core for
years. `sim_time_issue` reports it like the format's own errors, at the `end` value (or at
the task that ends last, when `end` is not given), with the wall time it would take at the
closed loop's measured pace; the CLI's `--max-sim-time SECONDS` raises the limit.
"""

from __future__ import annotations

from locoplan.exceptions import ScenarioIssue
from locoplan.scenario.loader import LoadedScenario
from locoplan.scenario.source import read_source
from locoplan.scenario.yaml_source import parse_yaml

DEFAULT_MAX_SIM_TIME = 3600.0  # s of simulated time
# Simulated seconds per wall-clock second of the closed loop with its log, on the slower
# scenes (package transfer measured 2.8x on one core; walk-square 4x): for the estimate.
REAL_TIME_FACTOR = 3.0


def wall_time_text(seconds: float) -> str:
    """A duration in the largest unit that keeps it readable: 40 s, 12 min, 5.6 h, 3.2 days,
    10.6 years."""
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    if seconds < 2 * 86400:
        return f"{seconds / 3600:.1f} h"
    if seconds < 2 * 365.25 * 86400:
        return f"{seconds / 86400:.1f} days"
    return f"{seconds / (365.25 * 86400):.3g} years"


def sim_time_issue(
    loaded: LoadedScenario, max_sim_time: float = DEFAULT_MAX_SIM_TIME
) -> ScenarioIssue | None:
    """The issue when `loaded` asks for more than `max_sim_time` s of simulated time, else
    None. Positioned at `end` (or the last task when `end` is absent)."""
    scenario = loaded.scenario
    end = scenario.end_time
    if end <= max_sim_time:
        return None
    # Only a refused script is parsed again, for the position of what asks for that long.
    doc = parse_yaml(read_source(loaded.label, loaded.text))
    if scenario.end is not None:
        line, column = doc.locate(("end",))
        what = f"end: {end:g} s"
    else:
        last = max(range(len(scenario.tasks)), key=lambda i: scenario.tasks[i].end)
        line, column = doc.locate(("tasks", last))
        what = f"the last task ends at {end:g} s (with the settle time)"
    message = (
        f"{what} of simulated time is more than the {max_sim_time:g} s allowed: it would take "
        f"about {wall_time_text(end / REAL_TIME_FACTOR)} of wall time at ~{REAL_TIME_FACTOR:g}x "
        f"real time; pass --max-sim-time {end:g} (or more) to run it anyway"
    )
    return ScenarioIssue(loaded.label, line, column, message)
