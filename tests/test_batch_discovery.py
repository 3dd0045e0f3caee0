"""Finding task scripts for `locoplan batch` (locoplan/batch/discovery.py)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from locoplan.batch.discovery import common_root, discover_scripts
from locoplan.batch.errors import BatchInputError


def _touch(path: Path) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("version: 1\n")
    return path


def test_directories_are_searched_recursively_sorted(tmp_path: Path) -> None:
    _touch(tmp_path / "b.yaml")
    _touch(tmp_path / "a.yml")
    _touch(tmp_path / "sub" / "deeper" / "c.YAML")
    _touch(tmp_path / "notes.txt")
    found = discover_scripts([tmp_path])
    names = [p.relative_to(tmp_path).as_posix() for p in found]
    assert names == ["a.yml", "b.yaml", "sub/deeper/c.YAML"]


def test_hidden_folders_are_skipped(tmp_path: Path) -> None:
    _touch(tmp_path / ".github" / "workflows" / "ci.yml")
    _touch(tmp_path / "runs" / ".cache" / "x.yaml")
    keep = _touch(tmp_path / "task.yaml")
    assert discover_scripts([tmp_path]) == [keep]


def test_files_and_dirs_mix_without_duplicates(tmp_path: Path) -> None:
    a = _touch(tmp_path / "a.yaml")
    b = _touch(tmp_path / "sub" / "b.yaml")
    named = _touch(tmp_path / "script.txt")  # named explicitly: taken whatever its suffix
    link = tmp_path / "link.yaml"
    os.symlink(a, link)
    found = discover_scripts([tmp_path / "sub", a, tmp_path, named, b])
    assert [p.resolve() for p in found] == sorted(
        {a.resolve(), b.resolve(), named.resolve()}, key=lambda p: p.as_posix()
    )
    assert len(found) == 3  # the symlink, b twice and a twice count once


def test_missing_path_is_an_input_error(tmp_path: Path) -> None:
    with pytest.raises(BatchInputError, match="no such file or directory") as info:
        discover_scripts([tmp_path / "nope"])
    assert info.value.path == str(tmp_path / "nope")


def test_nothing_found_is_an_input_error(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    with pytest.raises(BatchInputError, match=r"no task scripts \(\*.yaml, \*.yml\) found"):
        discover_scripts([tmp_path / "empty"])


def test_common_root_is_the_deepest_shared_folder(tmp_path: Path) -> None:
    a = _touch(tmp_path / "s" / "x" / "a.yaml")
    b = _touch(tmp_path / "s" / "y" / "b.yaml")
    assert common_root([a, b]) == (tmp_path / "s").resolve()
    assert common_root([a]) == (tmp_path / "s" / "x").resolve()
