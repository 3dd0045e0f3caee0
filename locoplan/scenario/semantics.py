"""Semantic rules of the task-script format: what types alone cannot check.

`check_semantics(scenario)` returns every violation as a `LocatedIssue` whose `loc` points
into the document (the offending task, or the offending name inside it):

- names: a task's `object` must be a declared object, `onto` a declared fixture whose kind
  has a top to place things on; `expect.placed` maps declared objects to declared fixtures;
- holding: an object is held from the end of its pick until a drop or throw starts. A drop or
  throw must start at or after the end of a pick of the same object with no drop or throw in
  between; a pick of an object already held (or still being picked) is an error; picking
  again after a drop or throw is fine. Tasks are taken in time order (start, then file order);
- timing: two locomotion tasks (step, walk, turn) may not overlap; two manipulation tasks
  (pick, drop, throw) may not overlap either (a locoplan rule beyond format v1: the arms do
  one thing at a time); no task may end after `end`;
- robot: a built-in robot (`hector`, `h1`), or a path ending in .yaml or .xml that exists
  (relative to the script).

Touching intervals (one ends exactly when the next starts) do not overlap; times are compared
with a tolerance of `TIME_EPS` so that decimal sums such as 0.1 + 0.2 do not count as overlaps.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from locoplan.scenario.messages import LocatedIssue, join, show, suggest
from locoplan.scenario.model import (
    LOCOMOTION_ACTIONS,
    MANIPULATION_ACTIONS,
    DropTask,
    PickTask,
    Scenario,
    ThrowTask,
)

# s; far below any meaningful task time (the MPC samples every 0.03 s), far above the
# rounding error of adding decimal times written with a few digits.
TIME_EPS = 1e-9

BUILTIN_ROBOTS = ("hector", "h1")
ROBOT_FILE_SUFFIXES = (".yaml", ".xml")
# Fixture kinds with a top surface that `drop onto` can place an object on.
DROP_TARGET_KINDS = ("table", "platform", "conveyor")

TaskLabel = Callable[[int], str]


def default_task_label(index: int) -> str:
    return f"task {index + 1}"


def check_semantics(
    scenario: Scenario,
    *,
    base_dir: Path | None = None,
    task_label: TaskLabel = default_task_label,
) -> list[LocatedIssue]:
    """Every semantic violation of `scenario`, in no particular order.

    `base_dir` is the directory an explicit robot path is relative to (the script's folder;
    the working directory when None). `task_label(i)` names task `i` (0-based) in messages
    that refer to another task, for example "task 2 at line 14".
    """
    issues: list[LocatedIssue] = []
    issues += _check_names(scenario)
    held_issues, flagged = _check_holding(scenario, task_label)
    issues += held_issues
    issues += _check_overlaps(scenario, LOCOMOTION_ACTIONS, task_label, set())
    issues += _check_overlaps(scenario, MANIPULATION_ACTIONS, task_label, flagged)
    issues += _check_end(scenario)
    issues += _check_robot(scenario, base_dir)
    return issues


def _declared(kind: str, names: list[str]) -> str:
    if not names:
        return f"no {kind} are declared (add them under '{kind}:')"
    return f"declared {kind}: {join(names)}"


def _check_names(scenario: Scenario) -> list[LocatedIssue]:
    issues: list[LocatedIssue] = []
    objects = list(scenario.objects)
    fixtures = list(scenario.fixtures)
    for i, task in enumerate(scenario.tasks):
        if isinstance(task, PickTask | DropTask | ThrowTask) and task.object not in objects:
            issues.append(
                LocatedIssue(
                    ("tasks", i, "object"),
                    f"unknown object {show(task.object)}; {_declared('objects', objects)}"
                    f"{suggest(task.object, objects)}",
                )
            )
        if isinstance(task, DropTask) and task.onto is not None:
            fixture = scenario.fixtures.get(task.onto)
            if fixture is None:
                issues.append(
                    LocatedIssue(
                        ("tasks", i, "onto"),
                        f"unknown fixture {show(task.onto)}; {_declared('fixtures', fixtures)}"
                        f"{suggest(task.onto, fixtures)}",
                    )
                )
            elif fixture.kind not in DROP_TARGET_KINDS:
                issues.append(
                    LocatedIssue(
                        ("tasks", i, "onto"),
                        f"cannot drop onto {show(task.onto)}, a {fixture.kind}: "
                        f"allowed fixture kinds: {join(DROP_TARGET_KINDS)}",
                    )
                )
    placed = scenario.expect.placed or {}
    for obj, fixture_name in placed.items():
        if obj not in scenario.objects:
            issues.append(
                LocatedIssue(
                    ("expect", "placed", obj, "[key]"),
                    f"unknown object {show(obj)} in expect.placed; "
                    f"{_declared('objects', objects)}{suggest(obj, objects)}",
                )
            )
        if fixture_name not in scenario.fixtures:
            issues.append(
                LocatedIssue(
                    ("expect", "placed", obj),
                    f"unknown fixture {show(fixture_name)} in expect.placed; "
                    f"{_declared('fixtures', fixtures)}{suggest(fixture_name, fixtures)}",
                )
            )
    return issues


def _time_order(scenario: Scenario) -> list[int]:
    return sorted(range(len(scenario.tasks)), key=lambda i: (scenario.tasks[i].start, i))


def _span(start: float, end: float) -> str:
    return f"{start:g}..{end:g} s"


def _check_holding(scenario: Scenario, label: TaskLabel) -> tuple[list[LocatedIssue], set[int]]:
    """Pick/drop/throw sequences per object; also returns the indices of flagged tasks."""
    issues: list[LocatedIssue] = []
    flagged: set[int] = set()
    tasks = scenario.tasks
    holder: dict[str, int] = {}  # object -> index of the pick holding it
    released_by: dict[str, int] = {}  # object -> index of the last drop/throw
    for i in _time_order(scenario):
        task = tasks[i]
        if not isinstance(task, PickTask | DropTask | ThrowTask):
            continue
        obj = task.object
        if obj not in scenario.objects:
            continue  # reported as an unknown name; holding it would only add noise
        name = show(obj)
        if isinstance(task, PickTask):
            if obj in holder:
                j = holder[obj]
                how = (
                    "still being picked" if task.start < tasks[j].end - TIME_EPS else "already held"
                )
                issues.append(
                    LocatedIssue(
                        ("tasks", i),
                        f"cannot pick {name} at {task.start:g} s: it is {how} "
                        f"(picked by {label(j)}, {_span(tasks[j].start, tasks[j].end)}) and "
                        "not dropped or thrown since",
                    )
                )
                flagged.add(i)
            else:
                holder[obj] = i
            continue
        verb = task.action
        if obj not in holder:
            if obj in released_by:
                k = released_by[obj]
                why = f"{label(k)} already released it ({tasks[k].action} at {tasks[k].start:g} s)"
            else:
                why = "no pick of it comes before"
            issues.append(
                LocatedIssue(
                    ("tasks", i),
                    f"cannot {verb} {name} at {task.start:g} s: it is not held then; {why} "
                    "(an object is held from the end of its pick until a drop or throw starts)",
                )
            )
            flagged.add(i)
            continue
        j = holder.pop(obj)
        released_by[obj] = i
        if task.start < tasks[j].end - TIME_EPS:
            issues.append(
                LocatedIssue(
                    ("tasks", i),
                    f"cannot {verb} {name} at {task.start:g} s: its pick ({label(j)}) ends only "
                    f"at {tasks[j].end:g} s; a {verb} must start at or after the end of the pick",
                )
            )
            flagged.add(i)
    return issues, flagged


def _check_overlaps(
    scenario: Scenario, actions: tuple[str, ...], label: TaskLabel, skip: set[int]
) -> list[LocatedIssue]:
    """Each task of `actions` that starts while an earlier one of `actions` still runs."""
    issues: list[LocatedIssue] = []
    tasks = scenario.tasks
    order = [i for i in _time_order(scenario) if tasks[i].action in actions]
    for pos, i in enumerate(order):
        if i in skip:
            continue
        for j in order[:pos]:
            # j starts no later than i; they overlap when j is still running at i's start.
            if (
                tasks[i].start < tasks[j].end - TIME_EPS
                and tasks[i].end > tasks[j].start + TIME_EPS
            ):
                a, b = tasks[i], tasks[j]
                if actions == LOCOMOTION_ACTIONS:
                    rule = "two locomotion tasks (step, walk, turn) cannot run at the same time"
                else:
                    rule = (
                        "manipulation tasks (pick, drop, throw) cannot overlap in time "
                        "(a locoplan rule in addition to format v1: "
                        "the arms do one thing at a time)"
                    )
                issues.append(
                    LocatedIssue(
                        ("tasks", i),
                        f"{a.action} ({_span(a.start, a.end)}) overlaps {label(j)} "
                        f"({b.action}, {_span(b.start, b.end)}): {rule}",
                    )
                )
                break
    return issues


def _check_end(scenario: Scenario) -> list[LocatedIssue]:
    if scenario.end is None:
        return []
    end = scenario.end
    return [
        LocatedIssue(
            ("tasks", i),
            f"{task.action} ends at {task.end:g} s, after end: {end:g} s; "
            "shorten or move the task, or raise 'end'",
        )
        for i, task in enumerate(scenario.tasks)
        if task.end > end + TIME_EPS
    ]


def _check_robot(scenario: Scenario, base_dir: Path | None) -> list[LocatedIssue]:
    robot = scenario.robot
    if robot in BUILTIN_ROBOTS:
        return []
    if not robot.endswith(ROBOT_FILE_SUFFIXES):
        return [
            LocatedIssue(
                ("robot",),
                f"unknown robot {show(robot)}; allowed: {join(BUILTIN_ROBOTS)}, or a path to a "
                f"robot file ending in {' or '.join(ROBOT_FILE_SUFFIXES)}"
                f"{suggest(robot, BUILTIN_ROBOTS)}",
            )
        ]
    path = resolve_robot_path(robot, base_dir)
    try:
        found = path.is_file()
    except (OSError, ValueError):  # a name too long, or with a NUL byte
        found = False
    if not found:
        return [
            LocatedIssue(
                ("robot",),
                f"robot file {show(robot)} not found (looked for {show(str(path))}); "
                "paths are relative to the task script",
            )
        ]
    return []


def resolve_robot_path(robot: str, base_dir: Path | None) -> Path:
    """Where an explicit robot file lives: `robot` itself if absolute, else `base_dir/robot`."""
    path = Path(robot)
    if path.is_absolute():
        return path
    return (base_dir if base_dir is not None else Path.cwd()) / path
