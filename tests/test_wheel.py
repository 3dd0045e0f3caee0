"""The built wheel works outside the checkout (issue 13, part 1).

The wheel is built from a copy of the sources (no build isolation: offline), checked for the
robot descriptions and example scripts it must carry, then installed without dependencies
into a temporary target. From an unrelated working directory, with only that target first on
the path, `locoplan examples` and `locoplan run` of a short script must work, the run's log
must read back with `locoplan inspect`, and numba's kernel cache must land in the per-user
folder because the installed package's folder is read-only (mode 555; when the tests run as
root, the subprocesses drop the capabilities that let root ignore permission bits).
"""

from __future__ import annotations

import ctypes
import json
import os
import shutil
import subprocess
import sys
import zipfile
from collections.abc import Iterator
from importlib import metadata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SOURCES = ("pyproject.toml", "setup.py", "README.md", "locoplan", "robots", "scenarios")
# prctl(PR_CAPBSET_DROP, cap): CAP_DAC_OVERRIDE and CAP_DAC_READ_SEARCH let root write where
# the mode bits say no.
_PR_CAPBSET_DROP = 24
_DAC_CAPS = (1, 2)

SHORT_STAND = """version: 1
name: short-stand
tasks:
  - {action: stand, start: 0.0, duration: 0.5}
end: 0.5
expect:
  no_fall: true
"""


def _setuptools_ok() -> bool:
    try:
        major = int(metadata.version("setuptools").split(".")[0])
    except (metadata.PackageNotFoundError, ValueError):
        return False
    return major >= 77


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The wheel, built from a copy of the sources (the checkout stays untouched)."""
    if not _setuptools_ok():
        pytest.skip("building the wheel offline needs setuptools>=77 (pip install -e '.[dev]')")
    base = tmp_path_factory.mktemp("wheel")
    src = base / "src"
    src.mkdir()
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "*.egg-info")
    for name in SOURCES:
        path = ROOT / name
        if path.is_dir():
            shutil.copytree(path, src / name, ignore=ignore)
        else:
            shutil.copy2(path, src / name)
    out = base / "dist"
    cmd = [sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "--no-build-isolation"]
    res = subprocess.run(
        [*cmd, "--no-index", "-q", "-w", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert res.returncode == 0, res.stdout + res.stderr
    (built,) = out.glob("locoplan-*.whl")
    return built


def test_wheel_carries_robots_scenarios_and_every_module(wheel: Path) -> None:
    names = set(zipfile.ZipFile(wheel).namelist())
    robots = {p.relative_to(ROOT / "robots").as_posix() for p in (ROOT / "robots").rglob("*")}
    for rel in robots:
        if (ROOT / "robots" / rel).is_file() and "__pycache__" not in rel:
            assert f"locoplan/_data/robots/{rel}" in names
    for script in (ROOT / "scenarios").glob("*.yaml"):
        assert f"locoplan/_data/scenarios/{script.name}" in names
    for module in (ROOT / "locoplan").rglob("*.py"):
        assert module.relative_to(ROOT).as_posix() in names
    assert not [n for n in names if "__pycache__" in n or n.endswith((".pyc", ".nbi", ".nbc"))]
    entry_points = next(n for n in names if n.endswith(".dist-info/entry_points.txt"))
    assert "locoplan = locoplan.cli:main" in zipfile.ZipFile(wheel).read(entry_points).decode()


def _drop_dac_caps() -> None:
    """In the child before exec: a root process loses the right to ignore mode bits."""
    libc = ctypes.CDLL(None, use_errno=True)
    for cap in _DAC_CAPS:
        if libc.prctl(_PR_CAPBSET_DROP, cap, 0, 0, 0) != 0:
            raise OSError(ctypes.get_errno(), "prctl(PR_CAPBSET_DROP) failed")


@pytest.fixture
def installed(wheel: Path, tmp_path: Path) -> Iterator[tuple[Path, Path]]:
    """(target, work): the wheel installed into `target`, its package folder read-only
    (mode 555), and a writable working folder holding the processes' home directory."""
    target, work = tmp_path / "target", tmp_path / "work"
    pip = [sys.executable, "-m", "pip", "install", "--no-deps", "--no-index", "-q"]
    res = subprocess.run(
        [*pip, "--target", str(target), str(wheel)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert res.returncode == 0, res.stdout + res.stderr
    (work / "home").mkdir(parents=True)
    package = target / "locoplan"
    folders = [package, *(p for p in package.rglob("*") if p.is_dir())]
    for folder in folders:
        folder.chmod(0o555)
    try:
        yield target, work
    finally:
        for folder in folders:
            folder.chmod(0o755)


def _locoplan(
    target: Path, work: Path, *args: str, timeout: float = 240
) -> subprocess.CompletedProcess[str]:
    env = {
        key: value
        for key, value in os.environ.items()
        if not key.startswith(("NUMBA_", "LOCOPLAN_", "XDG_", "PYTHON"))
    }
    env.update(
        PYTHONPATH=str(target),
        HOME=str(work / "home"),
        MPLCONFIGDIR=str(work / "home" / "mpl"),
        PYTHONDONTWRITEBYTECODE="1",
    )
    return subprocess.run(
        [sys.executable, "-m", "locoplan", *args],
        cwd=work,
        env=env,
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
        preexec_fn=_drop_dac_caps if os.geteuid() == 0 else None,
    )


@pytest.mark.closed_loop
def test_installed_wheel_runs_from_anywhere(installed: tuple[Path, Path]) -> None:
    target, work = installed
    package = target / "locoplan"
    res = _locoplan(target, work, "examples", "examples")
    assert res.returncode == 0, res.stderr
    assert (work / "examples" / "package-transfer.yaml").read_text() == (
        ROOT / "scenarios" / "package-transfer.yaml"
    ).read_text()

    (work / "short-stand.yaml").write_text(SHORT_STAND)
    res = _locoplan(
        target, work, "run", "short-stand.yaml", "--quiet", "--out", "runs",
        "--metrics-json", "m.json",
    )  # fmt: skip
    assert res.returncode == 0, res.stdout + res.stderr
    metrics = json.loads((work / "m.json").read_text())
    assert metrics["fell"] is False and metrics["completed"] is True
    log = work / "runs" / "short-stand.mcap"
    assert log.is_file()

    res = _locoplan(target, work, "inspect", str(log), timeout=120)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "short-stand" in res.stdout

    # The package folder was read-only: the kernels went to the per-user cache, not into it.
    cache = work / "home" / ".cache" / "locoplan" / "numba"
    assert list(cache.rglob("*.nbi")), f"no numba cache index under {cache}"
    assert not list(package.rglob("*.nbi"))
    # The process really ran the installed package (PYTHONPATH first), with its own robots.
    res = subprocess.run(
        [sys.executable, "-c", "import locoplan.robot.description as d; print(d.robots_dir())"],
        cwd=work,
        env={**os.environ, "PYTHONPATH": str(target)},
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert res.returncode == 0, res.stderr
    assert Path(res.stdout.strip()) == (package / "_data" / "robots").resolve()
