"""Result cache: a run whose inputs did not change is not simulated again.

The key is the SHA-256 of everything a run's result depends on: the script's exact text, the
contents of every locoplan source file and robot file (the built-in `robots/` directory and,
for a script naming its own robot file, that file's folder), the versions of Python and of the
numeric libraries, and the run options (strategy, model, output path, ...). Editing a script,
the controller or a robot, or upgrading MuJoCo, changes the key. Only runs that finished
(passed or failed) are stored; errors (a crash, a timeout) are always run again. Entries are
JSON files under `<out>/.cache/`; deleting the folder empties the cache.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import os
import platform
from collections.abc import Mapping
from importlib import metadata
from pathlib import Path
from typing import Any

import locoplan
from locoplan.batch.job import Job, Outcome

CACHE_DIRNAME = ".cache"
# Bump when the stored format or the meaning of a key changes.
CACHE_FORMAT = 1
# Libraries whose version can change a run's numbers.
_LIBRARIES = ("mujoco", "pin", "numpy", "scipy", "daqp", "proxsuite", "piqp")
# Robot files larger than this are hashed by size and mtime only (meshes are big and rare).
_MAX_HASHED_BYTES = 16 * 1024 * 1024


def _hash_tree(h: Any, root: Path, pattern: str) -> None:
    if not root.is_dir():
        return
    for path in sorted(root.rglob(pattern)):
        if not path.is_file() or "__pycache__" in path.parts or path.suffix == ".pyc":
            continue
        h.update(path.relative_to(root).as_posix().encode())
        h.update(b"\0")
        _hash_file(h, path)


def _hash_file(h: Any, path: Path) -> None:
    stat = path.stat()
    if stat.st_size > _MAX_HASHED_BYTES:
        h.update(f"{stat.st_size}:{stat.st_mtime_ns}".encode())
    else:
        h.update(path.read_bytes())
    h.update(b"\0")


def code_fingerprint() -> str:
    """SHA-256 of locoplan's source, the built-in robots and the library versions."""
    from locoplan.robot.description import robots_dir

    h = hashlib.sha256(f"locoplan-cache-{CACHE_FORMAT}\0".encode())
    _hash_tree(h, Path(locoplan.__file__).resolve().parent, "*")
    _hash_tree(h, robots_dir(), "*")
    h.update(f"python {platform.python_version()}\0".encode())
    for name in _LIBRARIES:
        try:
            version = metadata.version(name)
        except metadata.PackageNotFoundError:
            version = "-"
        h.update(f"{name} {version}\0".encode())
    return h.hexdigest()


def robot_fingerprint(robot_path: Path | None) -> str:
    """SHA-256 of the folder of a script's own robot file (None: a built-in robot, already
    covered by `code_fingerprint`)."""
    if robot_path is None:
        return "-"
    h = hashlib.sha256()
    _hash_tree(h, robot_path.resolve().parent, "*")
    return h.hexdigest()


def _plain(value: Any) -> Any:
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, Path):
        return value.as_posix()
    return value


def cache_key(job: Job, code: str, robot: str = "-") -> str:
    """The cache key of `job` given `code_fingerprint()` and `robot_fingerprint(...)`."""
    payload = {
        "text": job.text,
        "options": _plain(job.options),
        "code": code,
        "robot": robot,
    }
    blob = json.dumps(payload, sort_keys=True, default=str, ensure_ascii=False)
    return hashlib.sha256(blob.encode()).hexdigest()


class ResultCache:
    """Finished outcomes stored as `<directory>/<key>.json`."""

    def __init__(self, directory: Path) -> None:
        self.directory = directory

    def _path(self, key: str) -> Path:
        return self.directory / f"{key}.json"

    def get(self, key: str, job_id: str) -> Outcome | None:
        """The stored outcome for `key` (marked cached, renamed `job_id`), or None when there
        is none, it cannot be read, or the MCAP log it points to is gone."""
        try:
            data = json.loads(self._path(key).read_text("utf-8"))
        except (OSError, ValueError):
            return None
        if not isinstance(data, Mapping) or data.get("format") != CACHE_FORMAT:
            return None
        metrics = data.get("metrics")
        if not isinstance(metrics, Mapping) or data.get("status") not in ("passed", "failed"):
            return None
        log = metrics.get("log")
        if log is not None and not Path(log).is_file():
            return None
        return Outcome(
            job_id,
            data["status"],
            metrics,
            str(data.get("message", "")),
            wall_time=float(data.get("wall_time", 0.0)),
            cached=True,
        )

    def put(self, key: str, outcome: Outcome) -> None:
        """Store a finished outcome (passed or failed; others are ignored). Best effort: a
        cache that cannot be written only costs a rerun."""
        if outcome.status not in ("passed", "failed") or outcome.metrics is None:
            return
        data = {
            "format": CACHE_FORMAT,
            "status": outcome.status,
            "message": outcome.message,
            "wall_time": outcome.wall_time,
            "metrics": dict(outcome.metrics),
        }
        path = self._path(key)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        with contextlib.suppress(OSError):
            self.directory.mkdir(parents=True, exist_ok=True)
            tmp.write_text(json.dumps(data, indent=1) + "\n", "utf-8")
            os.replace(tmp, path)
