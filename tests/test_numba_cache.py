"""Where numba's kernel cache goes (locoplan._numba_cache, issue 13): next to the sources when
they are writable, else the per-user cache, else the temp dir; the user's NUMBA_CACHE_DIR wins.
The read-only installed package itself is tried in tests/test_wheel.py."""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from locoplan import _numba_cache
from locoplan._numba_cache import CACHE_ENV, choose_cache_dir, configure, user_cache_dir


@pytest.fixture(autouse=True)
def _restore_cache_env() -> Iterator[None]:
    """Put NUMBA_CACHE_DIR back as it was: `configure` sets it in this process, and
    monkeypatch's delenv of a variable that was not set records nothing to undo. Left set, it
    sent every later subprocess of the pytest-xdist worker to a fresh, empty cache, and the
    first of them compiled every kernel again (50-60 s of one core in each suite run)."""
    before = os.environ.get(CACHE_ENV)
    yield
    if before is None:
        os.environ.pop(CACHE_ENV, None)
    else:
        os.environ[CACHE_ENV] = before


@pytest.fixture
def package(tmp_path: Path) -> Path:
    root = tmp_path / "locoplan"
    for name in _numba_cache._KERNEL_DIRS:
        (root / name).mkdir(parents=True)
    return root


@pytest.fixture
def read_only(monkeypatch: pytest.MonkeyPatch) -> None:
    # Mode bits do not stop root; pretend every source folder is read-only.
    monkeypatch.setattr(_numba_cache, "_writable", lambda directory: False)


def test_writable_sources_keep_numba_default(package: Path) -> None:
    assert choose_cache_dir(package) is None


@pytest.mark.skipif(sys.platform in ("win32", "darwin"), reason="XDG layout")
def test_read_only_sources_use_the_user_cache(
    package: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, read_only: None
) -> None:
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    monkeypatch.delenv(CACHE_ENV, raising=False)
    expected = tmp_path / "xdg" / "locoplan" / "numba"
    assert user_cache_dir() == expected
    assert configure(package) == expected
    assert os.environ[CACHE_ENV] == str(expected)
    assert expected.is_dir()


@pytest.mark.skipif(sys.platform in ("win32", "darwin"), reason="XDG layout")
def test_default_user_cache_is_under_home(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path))
    assert user_cache_dir() == tmp_path / ".cache" / "locoplan" / "numba"


def test_unwritable_home_falls_back_to_the_temp_dir(
    package: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, read_only: None
) -> None:
    blocked = tmp_path / "file-not-dir"
    blocked.write_text("")
    monkeypatch.setattr(_numba_cache, "user_cache_dir", lambda: blocked / "numba")
    monkeypatch.setattr(_numba_cache.tempfile, "gettempdir", lambda: str(tmp_path / "tmp"))
    chosen = choose_cache_dir(package)
    assert chosen is not None and chosen.parent == tmp_path / "tmp"
    assert chosen.name.startswith("locoplan-numba-") and chosen.is_dir()


def test_the_users_setting_wins(
    package: Path, monkeypatch: pytest.MonkeyPatch, read_only: None
) -> None:
    monkeypatch.setenv(CACHE_ENV, "/somewhere/else")
    assert configure(package) is None
    assert os.environ[CACHE_ENV] == "/somewhere/else"


def test_already_imported_numba_is_told_directly(
    package: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, read_only: None
) -> None:
    import numba.core.config

    monkeypatch.delenv(CACHE_ENV, raising=False)
    monkeypatch.setattr(numba.core.config, "CACHE_DIR", numba.core.config.CACHE_DIR)
    monkeypatch.setattr(_numba_cache, "user_cache_dir", lambda: tmp_path / "cache")
    assert configure(package) == tmp_path / "cache"
    assert str(tmp_path / "cache") == numba.core.config.CACHE_DIR


def test_the_checkout_caches_next_to_the_sources() -> None:
    # Imported from a writable checkout: numba's default (in-tree __pycache__) stays.
    package = Path(_numba_cache.__file__).resolve().parent
    if os.access(package / "control", os.W_OK):
        assert choose_cache_dir(package) is None
