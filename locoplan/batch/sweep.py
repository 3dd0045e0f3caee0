"""Parameter sweeps: a grid over dotted keys of a task script, each point a validated script.

`--set KEY=VALUES` names a value in the YAML by its dotted path: mapping keys by name, list
items by 0-based index (`tasks.1.start` is the second task's start). VALUES is a range
`START:STOP:STEP` (STOP included when the steps land on it) or a comma list (`0.3,0.4`,
`true,false`, `left,right`). A missing mapping key is created (`gait.period` on a script
without `gait`), so a misspelt key shows up as that point's validation error. Every point is
the original text with its values set (comments and layout kept) and validated as a script
before anything runs: an invalid point is reported with its key, value and the validator's
`file:line:column: message`, and not simulated. Running the points and their CSV:
`locoplan.batch.sweep_results`.
"""

from __future__ import annotations

import io
import itertools
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from ruamel.yaml import YAML
from ruamel.yaml.error import YAMLError

from locoplan.batch.errors import SweepSpecError
from locoplan.batch.job import Job
from locoplan.exceptions import ScenarioError
from locoplan.sim.run import RunOptions

Scalar = int | float | bool | str

# A sweep larger than this is almost surely a typo in a range.
MAX_POINTS = 10_000

_KEY = re.compile(r"^[A-Za-z0-9_-]+(\.[A-Za-z0-9_-]+)*$")
_INT = re.compile(r"^[+-]?\d+$")


@dataclass(frozen=True, slots=True)
class SweepAxis:
    """One `--set`: the dotted `key`, its `path` (str keys, int list indices) and values."""

    key: str
    path: tuple[str | int, ...]
    values: tuple[Scalar, ...]


@dataclass(frozen=True, slots=True)
class SweepPoint:
    """One grid point: `index` in sorted order, one value per axis, and either the script
    `text` to run or the validation `error` (`key=value: file:line:col: message`)."""

    index: int
    values: tuple[Scalar, ...]
    text: str | None
    error: str | None


def _number(text: str) -> int | float | None:
    text = text.strip()
    if _INT.match(text):
        return int(text)
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _scalar(text: str) -> Scalar:
    text = text.strip()
    number = _number(text)
    if number is not None:
        return number
    if text.lower() in ("true", "false"):
        return text.lower() == "true"
    return text


def _tidy(value: float) -> float:
    # start + i * step accumulates binary noise (0.1 * 3 = 0.30000000000000004): keep 12
    # significant digits, far below any physical resolution and above float noise.
    return float(f"{value:.12g}")


def parse_values(spec: str, text: str) -> tuple[Scalar, ...]:
    """VALUES of a `--set`: `START:STOP:STEP` (inclusive) or a comma list."""
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise SweepSpecError(spec, f"a range is START:STOP:STEP, got '{text}'")
        numbers = [_number(p) for p in parts]
        if any(n is None for n in numbers):
            raise SweepSpecError(spec, f"a range needs three numbers, got '{text}'")
        start, stop, step = (n for n in numbers if n is not None)
        if step == 0 or (stop - start) * step < 0:
            raise SweepSpecError(spec, f"STEP {step} never gets from {start} to {stop}")
        count = math.floor((stop - start) / step + 1e-9) + 1
        if count > MAX_POINTS:
            raise SweepSpecError(spec, f"{count} values (at most {MAX_POINTS})")
        if all(isinstance(n, int) for n in (start, stop, step)):
            return tuple(int(start + i * step) for i in range(count))
        return tuple(_tidy(start + i * step) for i in range(count))
    items = [item for item in text.split(",")]
    if any(not item.strip() for item in items):
        raise SweepSpecError(spec, f"empty value in '{text}'")
    return tuple(_scalar(item) for item in items)


def parse_set(spec: str) -> SweepAxis:
    """A `--set KEY=VALUES` option as an axis; SweepSpecError when malformed."""
    key, sep, values = spec.partition("=")
    key = key.strip()
    if not sep or not values.strip():
        raise SweepSpecError(spec, "expected KEY=VALUES, e.g. objects.package.mass=1:14:1")
    if not _KEY.match(key):
        raise SweepSpecError(spec, f"'{key}' is not a dotted key such as tasks.1.start")
    path = tuple(int(p) if p.isdigit() else p for p in key.split("."))
    return SweepAxis(key, path, parse_values(spec, values.strip()))


def _yaml() -> YAML:
    yaml = YAML(typ="rt")
    yaml.preserve_quotes = True
    yaml.width = 4096  # never re-wrap long lines: line numbers stay those of the file
    yaml.indent(mapping=2, sequence=4, offset=2)  # the `  - ` lists of the format's examples
    return yaml


def _set_path(doc: Any, axis: SweepAxis, value: Scalar) -> None:
    node = doc
    for depth, part in enumerate(axis.path):
        last = depth == len(axis.path) - 1
        where = ".".join(str(p) for p in axis.path[: depth + 1])
        if isinstance(node, list):
            if not isinstance(part, int):
                raise SweepSpecError(f"{axis.key}=...", f"{where}: a list takes an index")
            if not 0 <= part < len(node):
                raise SweepSpecError(
                    f"{axis.key}=...",
                    f"{where}: index out of range (the list has {len(node)} items, "
                    f"indices 0..{len(node) - 1})",
                )
        elif isinstance(node, dict):
            if isinstance(part, int) and part not in node:
                part = str(part)
            if not last and part not in node:
                node[part] = {}
        else:
            raise SweepSpecError(f"{axis.key}=...", f"{where}: the parent is not a mapping")
        if last:
            node[part] = value
        else:
            node = node[part]


def _point_text(yaml: YAML, text: str, axes: Sequence[SweepAxis], values: Sequence[Scalar]) -> str:
    doc = yaml.load(text)
    if not isinstance(doc, dict):
        raise SweepSpecError(axes[0].key, "the script's top level is not a mapping")
    for axis, value in zip(axes, values, strict=True):
        _set_path(doc, axis, value)
    stream = io.StringIO()
    yaml.dump(doc, stream)
    return stream.getvalue()


def _sort_key(values: Sequence[Scalar]) -> tuple[tuple[int, Any], ...]:
    # Numbers before booleans before text, so mixed lists still sort.
    def one(v: Scalar) -> tuple[int, Any]:
        if isinstance(v, bool):
            return (1, v)
        if isinstance(v, int | float):
            return (0, v)
        return (2, v)

    return tuple(one(v) for v in values)


def point_label(axes: Sequence[SweepAxis], values: Sequence[Scalar]) -> str:
    """`key=value,key=value` for messages and job ids."""
    return ",".join(f"{a.key}={format_value(v)}" for a, v in zip(axes, values, strict=True))


def build_points(source: str | Path, text: str, axes: Sequence[SweepAxis]) -> list[SweepPoint]:
    """Every grid point of `axes` applied to the script `text` (read from `source`), sorted
    by value and validated. Raises SweepSpecError for a key that cannot be set (an index past
    the end of a list, a key below a scalar) or a grid of more than MAX_POINTS points."""
    from locoplan.scenario import load_scenario_file

    if not axes:
        raise SweepSpecError("", "give at least one --set KEY=VALUES")
    keys = [a.key for a in axes]
    if len(set(keys)) != len(keys):
        raise SweepSpecError(keys[0], "each key may be set once")
    size = math.prod(len(a.values) for a in axes)
    if size > MAX_POINTS:
        raise SweepSpecError(axes[0].key, f"{size} points in the grid (at most {MAX_POINTS})")
    yaml = _yaml()
    try:
        yaml.load(text)
    except YAMLError as exc:
        raise SweepSpecError("", f"{source}: not valid YAML: {exc}") from None
    grid = sorted(itertools.product(*(a.values for a in axes)), key=_sort_key)
    points: list[SweepPoint] = []
    for index, values in enumerate(grid):
        point_text = _point_text(yaml, text, axes, values)
        label = point_label(axes, values)
        try:
            load_scenario_file(source, point_text)
        except ScenarioError as exc:
            problems = "; ".join(str(issue) for issue in exc.issues)
            points.append(SweepPoint(index, values, None, f"{label}: invalid: {problems}"))
            continue
        points.append(SweepPoint(index, values, point_text, None))
    return points


def sweep_jobs(
    points: Sequence[SweepPoint],
    axes: Sequence[SweepAxis],
    name: str,
    source: str | Path,
    out_dir: Path,
    options: RunOptions | None = None,
) -> list[Job]:
    """One job per valid point; point i logs to `out_dir/<name>-<i:04d>.mcap`."""
    options = options or RunOptions()
    jobs = []
    for point in points:
        if point.text is None:
            continue
        log_name = f"{name}-{point.index:04d}"
        jobs.append(
            Job(
                point_label(axes, point.values),
                name,
                str(source),
                point.text,
                replace(options, out_dir=out_dir, log_name=log_name, log=True),
            )
        )
    return jobs


def format_value(value: Any) -> str:
    """How a value is written in the CSV: `true`/`false`, empty for None, `repr` for floats
    (shortest round-trip form: the same float always gives the same text)."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else ""
    return str(value)
