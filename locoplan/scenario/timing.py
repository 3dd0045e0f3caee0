"""Re-timing a validated scenario (`locoplan run --duration-scale K`)."""

from __future__ import annotations

from locoplan.scenario.model import Scenario


def scale_timing(scenario: Scenario, k: float) -> Scenario:
    """The same scenario with every task's start and duration, and `end`, multiplied by `k`
    (k > 1 runs the tasks more slowly). Gait timing is not scaled."""
    if not k > 0:
        raise ValueError(f"duration scale must be positive, got {k}")
    tasks = [
        t.model_copy(update={"start": t.start * k, "duration": t.duration * k})
        for t in scenario.tasks
    ]
    end = None if scenario.end is None else scenario.end * k
    return scenario.model_copy(update={"tasks": tasks, "end": end})
