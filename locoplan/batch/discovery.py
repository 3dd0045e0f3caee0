"""Finding task scripts: files given as they are, directories searched for `*.yaml` / `*.yml`."""

from __future__ import annotations

import os.path
from collections.abc import Sequence
from pathlib import Path

from locoplan.batch.errors import BatchInputError

SCRIPT_SUFFIXES = (".yaml", ".yml")


def discover_scripts(paths: Sequence[str | Path]) -> list[Path]:
    """The task scripts named by `paths`, sorted by path and without duplicates.

    A file is taken whatever its suffix (the user named it); a directory contributes every
    `*.yaml` / `*.yml` file below it, recursively, skipping hidden files and directories
    (`.git`, `.github`, a `.cache`). Duplicates (the same file reached twice, through
    different spellings or symlinks) keep their first spelling.

    Raises BatchInputError for a path that does not exist, or when nothing is found.
    """
    found: dict[Path, Path] = {}
    for raw in paths:
        path = Path(raw)
        if path.is_dir():
            candidates = sorted(
                p
                for p in path.rglob("*")
                if p.suffix.lower() in SCRIPT_SUFFIXES
                and p.is_file()
                and not any(part.startswith(".") for part in p.relative_to(path).parts)
            )
        elif path.is_file():
            candidates = [path]
        else:
            raise BatchInputError(f"{raw}: no such file or directory", str(raw))
        for candidate in candidates:
            found.setdefault(candidate.resolve(), candidate)
    if not found:
        shown = " ".join(str(p) for p in paths)
        raise BatchInputError(f"no task scripts (*.yaml, *.yml) found in {shown}")
    return sorted(found.values(), key=lambda p: p.as_posix())


def common_root(files: Sequence[Path]) -> Path:
    """The deepest directory holding every file of `files` (absolute); outputs mirror the
    scripts' layout below it."""
    parents = [str(f.resolve().parent) for f in files]
    return Path(os.path.commonpath(parents))
