"""Where numba caches locoplan's compiled kernels.

Numba writes each `cache=True` kernel next to its source, in `__pycache__`. That works in a
checkout and in a package installed where the user may write; when the installed package's
folder is read-only (a system-wide install, a container image, `pip install --target` on a
read-only mount) the kernels go to a per-user cache instead:

- `$XDG_CACHE_HOME/locoplan/numba` (default `~/.cache/locoplan/numba`) on Linux and others,
- `~/Library/Caches/locoplan/numba` on macOS,
- `%LOCALAPPDATA%\\locoplan\\Cache\\numba` on Windows,

or, when that cannot be created either, `<temp dir>/locoplan-numba-<user>`. The choice is made
once, by `configure()` from `locoplan/__init__.py`, before any module imports numba; it is
handed to numba through `NUMBA_CACHE_DIR`, and a `NUMBA_CACHE_DIR` the user set always wins.
"""

from __future__ import annotations

import getpass
import os
import sys
import tempfile
from pathlib import Path

CACHE_ENV = "NUMBA_CACHE_DIR"
# Package folders that hold `cache=True` kernels (control/, log/, plan/, sim/).
_KERNEL_DIRS = ("control", "log", "plan", "sim")


def _writable(directory: Path) -> bool:
    """Whether numba can cache next to the sources of `directory` (in its `__pycache__`)."""
    pycache = directory / "__pycache__"
    target = pycache if pycache.is_dir() else directory
    return os.access(target, os.W_OK | os.X_OK)


def user_cache_dir() -> Path:
    """The per-user cache folder for locoplan's kernels (not created)."""
    if sys.platform == "win32":
        base = os.environ.get("LOCALAPPDATA") or str(Path.home() / "AppData" / "Local")
        return Path(base) / "locoplan" / "Cache" / "numba"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / "locoplan" / "numba"
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "locoplan" / "numba"


def _temp_cache_dir() -> Path:
    try:
        user = getpass.getuser()
    except (KeyError, OSError):  # no name for this uid (containers)
        user = str(os.getuid()) if hasattr(os, "getuid") else "user"
    return Path(tempfile.gettempdir()) / f"locoplan-numba-{user}"


def _usable(directory: Path) -> bool:
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except (OSError, RuntimeError):  # RuntimeError: no home directory to expand
        return False
    return os.access(directory, os.W_OK | os.X_OK)


def choose_cache_dir(package_dir: Path) -> Path | None:
    """None when numba can cache next to the sources under `package_dir`; otherwise the
    folder to cache in (created): the per-user cache, else a folder in the temp dir."""
    if all(_writable(package_dir / name) for name in _KERNEL_DIRS):
        return None
    try:
        preferred = user_cache_dir()
    except RuntimeError:  # no home directory
        preferred = _temp_cache_dir()
    for candidate in (preferred, _temp_cache_dir()):
        if _usable(candidate):
            return candidate
    return None  # nowhere to write: numba compiles in memory and warns


def configure(package_dir: Path | None = None) -> Path | None:
    """Point numba's cache at `choose_cache_dir` unless the user set NUMBA_CACHE_DIR; returns
    the folder chosen (None: next to the sources, or the user's own setting)."""
    if os.environ.get(CACHE_ENV):
        return None
    if package_dir is None:
        package_dir = Path(__file__).resolve().parent
    chosen = choose_cache_dir(package_dir)
    if chosen is None:
        return None
    os.environ[CACHE_ENV] = str(chosen)
    config = sys.modules.get("numba.core.config")
    if config is not None:  # numba already imported (by the user's code): tell it directly
        config.CACHE_DIR = str(chosen)  # type: ignore[attr-defined]
    return chosen
