"""locoplan.scenario.source: reading a task script's text."""

from __future__ import annotations

import io
import sys
from pathlib import Path

import pytest

from locoplan.exceptions import ScenarioError
from locoplan.scenario.source import MAX_BYTES, read_source


def message(source: str | Path, text: str | bytes | None = None) -> str:
    with pytest.raises(ScenarioError) as info:
        read_source(source, text)
    [issue] = info.value.issues
    return str(issue)


def test_file_text_and_label(tmp_path: Path) -> None:
    path = tmp_path / "a.yaml"
    path.write_bytes("\ufeffname: café\n".encode())
    src = read_source(path)
    assert (src.label, src.path, src.text) == (str(path), path, "name: café\n")  # BOM dropped
    assert read_source(str(path)).label == str(path)


def test_given_text_is_named_by_source() -> None:
    src = read_source("some/where.yaml", b"a: 1\n")
    assert (src.label, src.path, src.text) == ("some/where.yaml", Path("some/where.yaml"), "a: 1\n")
    src = read_source("-", "a: 1\n")
    assert (src.label, src.path) == ("<stdin>", None)


def test_stdin_is_read_when_no_text_is_given(monkeypatch: pytest.MonkeyPatch) -> None:
    fake = io.TextIOWrapper(io.BytesIO(b"a: 1\n"), encoding="utf-8")
    monkeypatch.setattr(sys, "stdin", fake)
    assert read_source("-").text == "a: 1\n"


def test_non_utf8_points_at_the_first_bad_byte() -> None:
    assert message("x.yaml", b"a: 1\nb: \xc3\xa9\xff\n") == (
        "x.yaml:2:5: not UTF-8 text: byte 0xff cannot be decoded; task scripts must be UTF-8"
    )


def test_size_limit() -> None:
    assert message("x.yaml", b"#" * (MAX_BYTES + 1)) == (
        f"x.yaml:1:1: file too large ({MAX_BYTES + 1} bytes); at most {MAX_BYTES} allowed"
    )
    assert read_source("x.yaml", b"#" * MAX_BYTES).text == "#" * MAX_BYTES


def test_missing_and_directory(tmp_path: Path) -> None:
    assert message(tmp_path / "nope.yaml") == f"{tmp_path / 'nope.yaml'}:1:1: no such file"
    assert message(tmp_path) == f"{tmp_path}:1:1: is a directory, not a task script file"
