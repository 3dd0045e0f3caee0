"""Loading a task script: YAML file -> validated `Scenario`, or a `ScenarioError` listing every
issue with its file, 1-based line and column, and a message that says what is wrong and what
is allowed.

Stages, each reporting all the issues it finds:
1. reading (missing file, directory, non-UTF-8 bytes, too large): `source`; YAML syntax
   (also duplicate keys, tags, too deep or too large after aliases): `yaml_source`;
2. structure and types with the pydantic models (`model`), each error mapped back to its node;
3. semantics (`semantics`): names, holding, overlaps, `end`, robot. This stage runs when the
   sections it reads (tasks, objects, fixtures, end, expect, robot) are valid, even if other
   sections have errors, so that one run reports as much as possible without follow-on noise.

Positions: a wrong value points at the value; an unknown key at the key; a missing key at the
mapping that lacks it (its first key, or its `{`); an unknown or missing `action` at the action
value or the task; a rule about a whole task (holding, overlap, `end`) at the task.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from pydantic import ValidationError

from locoplan.exceptions import ScenarioError, ScenarioIssue
from locoplan.scenario.feasibility import check_feasibility, robot_geometry
from locoplan.scenario.messages import LocatedIssue, show, validation_issues
from locoplan.scenario.model import Scenario
from locoplan.scenario.semantics import BUILTIN_ROBOTS, check_semantics, resolve_robot_path
from locoplan.scenario.source import STDIN_LABEL, read_source
from locoplan.scenario.yaml_source import YamlDocument, parse_yaml

# Past this many issues the rest are summarised in one line: a file that bad needs fixing
# from the top anyway, and a megabyte of garbage should not print a megabyte of errors.
MAX_ISSUES = 100

# Pydantic errors turned into messages at most (the rest are only counted).
_MAX_TRANSLATED = 1000

# Top-level sections the semantic checks read.
_SEMANTIC_SECTIONS = ("tasks", "objects", "fixtures", "end", "expect", "robot")


@dataclass(frozen=True, slots=True)
class LoadedScenario:
    """A validated task script with its source.

    `path` is the file as given (None when read from standard input); `text` is the file's
    exact text (UTF-8 decoded, a leading BOM removed), for logs that embed the script.
    """

    scenario: Scenario
    path: Path | None
    text: str

    @property
    def label(self) -> str:
        """How messages name the script: its path, or `<stdin>`."""
        return str(self.path) if self.path is not None else STDIN_LABEL

    @property
    def robot_path(self) -> Path | None:
        """The robot file named by `robot` (resolved against the script's folder), or None
        for a built-in robot such as `hector`."""
        robot = self.scenario.robot
        if robot in BUILTIN_ROBOTS:
            return None
        base_dir = self.path.parent if self.path is not None else None
        return resolve_robot_path(robot, base_dir)


def load_scenario(source: str | Path, text: str | bytes | None = None) -> Scenario:
    """Load and validate a task script; see `load_scenario_file`, which also returns the text."""
    return load_scenario_file(source, text).scenario


def load_scenario_file(source: str | Path, text: str | bytes | None = None) -> LoadedScenario:
    """Load and validate the task script `source`.

    `source` is a file path, or "-" for standard input (named `<stdin>` in messages; read
    here when `text` is None). When `text` (str, or bytes that must be UTF-8) is given it is
    used instead of reading the file, and `source` only names it (and locates a relative
    robot path).

    Raises ScenarioError holding every issue found, sorted by position. Never raises
    another exception type for bad input.
    """
    src = read_source(source, text)
    doc = parse_yaml(src)
    label = src.label

    def place(issue: LocatedIssue) -> ScenarioIssue:
        line, column = doc.locate(issue.loc)
        return ScenarioIssue(label, line, column, issue.message)

    if doc.data is None:
        message = "empty task script; expected a mapping with at least version, name and tasks"
        raise ScenarioError([ScenarioIssue(label, 1, 1, message)])
    if not isinstance(doc.data, dict):
        line, column = doc.locate(())
        message = (
            f"the top level must be a mapping with keys such as version, name and tasks, "
            f"got {show(doc.data)}"
        )
        raise ScenarioError([ScenarioIssue(label, line, column, message)])

    located: list[LocatedIssue] = []
    scenario: Scenario | None = None
    untranslated = 0
    try:
        scenario = Scenario.model_validate(doc.data)
    except ValidationError as exc:
        errors = exc.errors(include_url=False)
        # Messages cost more than positions; a file with thousands of errors is cut anyway.
        located += validation_issues(errors[:_MAX_TRANSLATED])
        untranslated = max(0, len(errors) - _MAX_TRANSLATED)
    checked = scenario if scenario is not None else _semantic_view(doc)
    if checked is not None:
        base_dir = src.path.parent if src.path is not None else None
        located += check_semantics(
            checked, base_dir=base_dir, task_label=lambda i: _task_label(doc, i)
        )
    if not located and scenario is not None:
        # What the robot cannot do, once the script is valid as a script.
        robot = scenario.robot
        if robot not in BUILTIN_ROBOTS:
            robot = str(resolve_robot_path(robot, src.path.parent if src.path else None))
        located += check_feasibility(scenario, robot_geometry(robot))
    if located:
        raise ScenarioError(_capped([place(issue) for issue in located], untranslated))
    assert scenario is not None  # no issue means validation succeeded
    if scenario.robot not in BUILTIN_ROBOTS:
        # A relative robot path names a file beside the script: make it absolute, so that
        # whoever loads the robot later (run, compare, render, batch workers) finds the same
        # file whatever their working directory.
        base = src.path.parent if src.path is not None else None
        absolute = str(resolve_robot_path(scenario.robot, base).resolve())
        scenario = scenario.model_copy(update={"robot": absolute})
    return LoadedScenario(scenario, src.path, src.text)


def locate_issue(source: str | Path, text: str, issue: LocatedIssue) -> ScenarioIssue:
    """The file position of `issue` (found after loading, e.g. by the plan compiler) in the
    script `source` whose text is `text` (as `load_scenario_file` read it)."""
    src = read_source(source, text)
    line, column = parse_yaml(src).locate(issue.loc)
    return ScenarioIssue(src.label, line, column, issue.message)


def _semantic_view(doc: YamlDocument) -> Scenario | None:
    """The document's semantic sections alone, validated, when they are valid by themselves."""
    data = doc.data
    view = {k: data[k] for k in _SEMANTIC_SECTIONS if k in data}
    view.update(version=1, name="semantic-view")
    try:
        return Scenario.model_validate(view)
    except ValidationError:
        return None


def _task_label(doc: YamlDocument, index: int) -> str:
    line, _ = doc.locate(("tasks", index))
    return f"task {index + 1} at line {line}"


def _capped(issues: list[ScenarioIssue], untranslated: int) -> list[ScenarioIssue]:
    """The first MAX_ISSUES issues by position, and a line counting the others."""
    if len(issues) <= MAX_ISSUES and not untranslated:
        return issues
    ordered = sorted(issues, key=lambda i: (i.line, i.column))
    rest = ordered[min(MAX_ISSUES, len(ordered) - 1)]
    hidden = len(ordered) - MAX_ISSUES + untranslated
    note = ScenarioIssue(
        rest.path,
        rest.line,
        rest.column,
        f"... and {hidden} more issues from here on (not shown)",
    )
    return [*ordered[:MAX_ISSUES], note]
