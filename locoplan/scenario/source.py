"""Reading a task script's text: from a file, from standard input, or as given.

Every failure becomes a `ScenarioError` at line 1, column 1 (or at the first bad byte):
a missing or unreadable file, a directory, a file too large, bytes that are not UTF-8.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path
from typing import NoReturn

from locoplan.exceptions import ScenarioError, ScenarioIssue

STDIN_LABEL = "<stdin>"

# A task script is a few kilobytes. ruamel.yaml's pure-Python round-trip loader needs about
# 10 s per megabyte here, so larger input is refused before parsing.
MAX_BYTES = 256 * 1024


@dataclass(frozen=True, slots=True)
class SourceText:
    """A task script's text and where it came from.

    `label` is what messages show (the path as given, or `<stdin>`); `path` is the file, or
    None for standard input.
    """

    label: str
    path: Path | None
    text: str


def read_source(source: str | Path, text: str | bytes | None = None) -> SourceText:
    """Read a task script: the file `source`, or `text` when given (`source` then only names
    it); `source` "-" stands for standard input, read here when `text` is None.

    Raises ScenarioError (at 1:1, or at the first bad byte) for a missing, unreadable,
    too large or non-UTF-8 file.
    """
    is_stdin = str(source) == "-"
    label = STDIN_LABEL if is_stdin else str(source)
    path = None if is_stdin else Path(source)
    if text is None:
        data = _read_stdin() if is_stdin else _read_file(label, Path(source))
    else:
        data = text
    if isinstance(data, bytes):
        if len(data) > MAX_BYTES:
            _fail(label, 1, 1, f"file too large ({len(data)} bytes); at most {MAX_BYTES} allowed")
        data = _decode(label, data)
    elif len(data) > MAX_BYTES:
        _fail(label, 1, 1, f"text too large ({len(data)} characters); at most {MAX_BYTES}")
    return SourceText(label, path, data.removeprefix("\ufeff"))


def _read_stdin() -> bytes | str:
    buffer = getattr(sys.stdin, "buffer", None)
    if buffer is not None:
        data: bytes | str = buffer.read(MAX_BYTES + 1)
    else:
        data = sys.stdin.read(MAX_BYTES + 1)
    return data


def _read_file(label: str, path: Path) -> bytes:
    try:
        with path.open("rb") as f:
            return f.read(MAX_BYTES + 1)
    except FileNotFoundError:
        _fail(label, 1, 1, "no such file")
    except IsADirectoryError:
        _fail(label, 1, 1, "is a directory, not a task script file")
    except PermissionError:
        _fail(label, 1, 1, "cannot read the file: permission denied")
    except OSError as exc:
        _fail(label, 1, 1, f"cannot read the file: {exc.strerror or exc}")


def _decode(label: str, data: bytes) -> str:
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line_start = data.rfind(b"\n", 0, exc.start) + 1
        line = data.count(b"\n", 0, exc.start) + 1
        column = len(data[line_start : exc.start].decode("utf-8", errors="replace")) + 1
        _fail(
            label,
            line,
            column,
            f"not UTF-8 text: byte 0x{data[exc.start]:02x} cannot be decoded; "
            "task scripts must be UTF-8",
        )


def _fail(label: str, line: int, column: int, message: str) -> NoReturn:
    raise ScenarioError([ScenarioIssue(label, line, column, message)])
