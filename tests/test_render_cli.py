"""`locoplan run --video` and `locoplan render` end to end in subprocesses: the same frames
from both, exit codes, messages that say what is wrong."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from test_render_video import CODEC_NOISE, decode, mean_abs_diff

from locoplan.log.writer import RunLogWriter

pytestmark = pytest.mark.closed_loop

LOCOPLAN = [sys.executable, "-m", "locoplan.cli"]
SHORT_STAND = """version: 1
name: short-stand
tasks:
  - {action: stand, start: 0.0, duration: 1.0}
end: 1.0
"""


def _run(args: list[str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [*LOCOPLAN, *args], capture_output=True, text=True, timeout=300, check=False
    )


def test_run_video_and_render_give_the_same_frames(tmp_path: Path) -> None:
    script = tmp_path / "stand.yaml"
    script.write_text(SHORT_STAND)
    live = tmp_path / "live.mp4"
    res = _run(["run", str(script), "--out", str(tmp_path), "--quiet", "--video", str(live)])
    assert res.returncode == 0, res.stderr
    log = tmp_path / "short-stand.mcap"
    again = tmp_path / "again.mp4"
    res = _run(["render", str(log), "--video", str(again)])
    assert res.returncode == 0, res.stderr
    assert "wrote" in res.stderr and "30 frames" in res.stderr and "Traceback" not in res.stderr
    a, b = decode(live), decode(again)
    # 1 s at 30 fps: frames at 0 .. 29/30 s, the last sample at 0.991 s.
    assert a.shape == (30, 480, 640, 3)
    assert mean_abs_diff(a, b) < CODEC_NOISE
    assert not list(tmp_path.glob("*.part.mp4"))  # written under a temporary name, renamed


def test_bad_inputs_exit_2_before_simulating(tmp_path: Path) -> None:
    script = tmp_path / "stand.yaml"
    script.write_text(SHORT_STAND)
    res = _run(["run", str(script), "--out", str(tmp_path), "--video", str(tmp_path / "x.avi")])
    assert res.returncode == 2 and ".mp4" in res.stderr
    assert not (tmp_path / "short-stand.mcap").exists()

    not_mcap = tmp_path / "notes.mcap"
    not_mcap.write_text("not a log\n")
    res = _run(["render", str(not_mcap), "--video", str(tmp_path / "v.mp4")])
    assert res.returncode == 2 and "not a readable MCAP log" in res.stderr
    res = _run(["render", str(tmp_path / "missing.mcap"), "--video", str(tmp_path / "v.mp4")])
    assert res.returncode == 2 and "no such file" in res.stderr
    assert "Traceback" not in res.stderr

    # A log without /sim/qpos (an older locoplan's, or another tool's) cannot be rendered.
    bare = tmp_path / "bare.mcap"
    with RunLogWriter(bare, scenario_name="short-stand", scenario_text=SHORT_STAND) as log:
        log.json("/robot/base", 0.0, {"position": np.zeros(3)})
    res = _run(["render", str(bare), "--video", str(tmp_path / "v.mp4")])
    assert res.returncode == 2 and "/sim/qpos" in res.stderr
    assert not (tmp_path / "v.mp4").exists()


def test_missing_opengl_names_the_packages(tmp_path: Path) -> None:
    script = tmp_path / "stand.yaml"
    script.write_text(SHORT_STAND)
    # glvnd finds no EGL vendor library through this variable: EGL is "not installed".
    env = {**os.environ, "__EGL_VENDOR_LIBRARY_FILENAMES": str(tmp_path / "none.json")}
    res = subprocess.run(
        [*LOCOPLAN, "run", str(script), "--out", str(tmp_path), "--video", str(tmp_path / "v.mp4")],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        env=env,
    )
    assert res.returncode == 2, res.stderr
    assert "libegl1" in res.stderr and "libosmesa6" in res.stderr
    assert not (tmp_path / "short-stand.mcap").exists()  # refused before simulating
    res = subprocess.run(
        [*LOCOPLAN, "run", str(script), "--video", str(tmp_path / "v.mp4")],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        env={**os.environ, "MUJOCO_GL": "glx"},
    )
    assert res.returncode == 2
    assert "MUJOCO_GL='glx'" in res.stderr and "egl, osmesa" in res.stderr
