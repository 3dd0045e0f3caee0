"""Closed-loop behaviour in MuJoCo, asserted from the simulation state (issue: stands, steps,
walks and turns). Each test runs the real controller (MPC + WBC) on the real MuJoCo model.

Positions and yaw come from the MuJoCo free joint (the record samples `data.qpos` every
10 ms); torques are what MuJoCo's actuators applied (`data.actuator_force`) at every step.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from locoplan.scenario import load_scenario_file
from locoplan.sim.loop import Push
from locoplan.sim.run import RunOptions, RunResult, run_scenario

pytestmark = pytest.mark.closed_loop

ROOT = Path(__file__).resolve().parents[1]
NOMINAL_HEIGHT = 0.60  # robots/hector/robot.yaml: trunk origin above the soles


def _run(tmp_path: Path, text: str, **options: object) -> RunResult:
    path = tmp_path / "task.yaml"
    path.write_text(text)
    loaded = load_scenario_file(path)
    return run_scenario(loaded.scenario, loaded.text, RunOptions(out_dir=tmp_path, **options))  # type: ignore[arg-type]


def _run_file(tmp_path: Path, name: str, **options: object) -> RunResult:
    loaded = load_scenario_file(ROOT / "scenarios" / name)
    return run_scenario(loaded.scenario, loaded.text, RunOptions(out_dir=tmp_path, **options))  # type: ignore[arg-type]


def _trajectory(result: RunResult) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rec = result.record
    t = np.asarray(rec.t)
    pos = np.asarray(rec.base_position)
    yaw = np.unwrap(np.asarray(rec.base_rpy)[:, 2])
    return t, pos, yaw


def _torques_within_limits(result: RunResult) -> None:
    # Measured on what MuJoCo applied; the actuators' ctrlrange equals the limit, so a ratio
    # above 1 cannot happen physically, and the controller must not even ask for it often.
    assert result.metrics["peak_torque_ratio"] <= 1.0
    assert result.metrics["torque_clips"] == 0, "the WBC asked for more than the torque limits"


def test_stands_ten_seconds(tmp_path: Path) -> None:
    result = _run_file(tmp_path, "stand.yaml")
    _, pos, _ = _trajectory(result)
    assert not result.metrics["fell"]
    assert result.record.sim_time >= 10.0 - 1e-6
    # Issue limits: height within 1 cm of nominal, horizontal drift under 2 cm.
    assert np.max(np.abs(pos[:, 2] - NOMINAL_HEIGHT)) < 0.01
    assert np.max(np.linalg.norm(pos[:, :2] - pos[0, :2], axis=1)) < 0.02
    _torques_within_limits(result)
    assert result.metrics["passed"]


def test_steps_in_place_ten_seconds(tmp_path: Path) -> None:
    result = _run_file(tmp_path, "step.yaml")
    _, pos, yaw = _trajectory(result)
    assert not result.metrics["fell"]
    assert result.record.sim_time >= 10.0 - 1e-6
    assert np.max(np.linalg.norm(pos[:, :2] - pos[0, :2], axis=1)) < 0.05
    assert np.max(np.abs(np.degrees(yaw))) < 5.0
    _torques_within_limits(result)


@pytest.mark.parametrize(("angle", "bound"), [(0.0, 0.03), (-110.0, 0.05)])
def test_long_swings_from_the_start_stay_in_place(
    tmp_path: Path, angle: float, bound: float
) -> None:
    """Stepping (or turning) in place from 0 s with swings of half the period: the plan's
    start lead (`plan.gait.start_lead`) lets the MPC shift the weight before the first
    lift-off. Without it the robot walked off sideways, 9.9 cm in 2.6 s stepping and 17 cm
    in the -110 deg turn (measured; with it 0.2 and 2.2 cm). Bounds: the issue's 5 cm
    stepping drift, 3 cm for the plain stepping."""
    text = f"""
version: 1
name: long-swings
gait: {{period: 0.5, swing: 0.25}}
tasks:
  - {{action: turn, angle: {angle}, start: 0.0, duration: 2.6}}
  - {{action: stand, start: 2.6, duration: 1.0}}
end: 3.6
"""
    if angle == 0.0:
        text = text.replace("action: turn, angle: 0.0,", "action: step,")
    result = _run(tmp_path, text)
    t, pos, yaw = _trajectory(result)
    assert not result.metrics["fell"]
    drift = np.linalg.norm(pos[:, :2] - pos[0, :2], axis=1)
    assert drift[np.searchsorted(t, 2.6)] < bound
    assert math.degrees(yaw[-1]) == pytest.approx(angle, abs=5.0)
    _torques_within_limits(result)


@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_survives_lateral_push_while_stepping(tmp_path: Path, direction: float) -> None:
    # 30 N for 0.1 s is the 3 N s impulse, applied mid-stance at t = 3 s.
    push = Push(start=3.0, duration=0.1, force=(0.0, 30.0 * direction, 0.0))
    text = (
        "version: 1\nname: push\ntasks:\n  - {action: step, start: 0.0, duration: 6.0}\nend: 6.5\n"
    )
    result = _run(tmp_path, text, pushes=(push,))
    _, pos, _ = _trajectory(result)
    assert not result.metrics["fell"]
    # The push moves the trunk sideways a few cm; the stepping recovers towards the start.
    assert np.max(np.abs(pos[:, 1])) > 0.01, "the push had no visible effect"
    assert np.linalg.norm(pos[-1, :2]) < 0.05
    _torques_within_limits(result)


def test_walks_forward_one_metre(tmp_path: Path) -> None:
    text = (
        "version: 1\nname: walk-forward\n"
        "tasks:\n  - {action: walk, distance: [1.0, 0.0], start: 0.3, duration: 3.4}\n"
        "end: 4.5\n"
    )
    result = _run(tmp_path, text)
    _, pos, yaw = _trajectory(result)
    assert not result.metrics["fell"]
    assert abs(pos[-1, 0] - 1.0) < 0.10
    assert abs(pos[-1, 1]) < 0.10
    assert abs(math.degrees(yaw[-1])) < 5.0
    _torques_within_limits(result)
    assert result.metrics["completed"]


def test_walks_sideways(tmp_path: Path) -> None:
    text = (
        "version: 1\nname: walk-side\n"
        "tasks:\n  - {action: walk, distance: [0.0, 0.3], start: 0.3, duration: 2.4}\n"
        "end: 3.5\n"
    )
    result = _run(tmp_path, text)
    _, pos, _ = _trajectory(result)
    assert not result.metrics["fell"]
    assert abs(pos[-1, 1] - 0.3) < 0.10
    assert abs(pos[-1, 0]) < 0.10
    _torques_within_limits(result)


def test_turns_ninety_degrees_in_place(tmp_path: Path) -> None:
    result = _run_file(tmp_path, "turn.yaml")
    _, pos, yaw = _trajectory(result)
    assert not result.metrics["fell"]
    assert abs(math.degrees(yaw[-1]) - 90.0) < 5.0
    assert np.linalg.norm(pos[-1, :2]) < 0.05
    _torques_within_limits(result)


def test_walks_while_turning(tmp_path: Path) -> None:
    text = (
        "version: 1\nname: walk-turn\n"
        "tasks:\n  - {action: walk, distance: [0.6, 0.0], angle: 60, start: 0.3, duration: 2.4}\n"
        "end: 3.5\n"
    )
    result = _run(tmp_path, text)
    _, pos, yaw = _trajectory(result)
    assert not result.metrics["fell"]
    assert abs(pos[-1, 0] - 0.6) < 0.10
    assert abs(pos[-1, 1]) < 0.10
    assert abs(math.degrees(yaw[-1]) - 60.0) < 5.0
    _torques_within_limits(result)


def test_walk_square_closes(tmp_path: Path) -> None:
    result = _run_file(tmp_path, "walk-square.yaml")
    _, pos, yaw = _trajectory(result)
    assert not result.metrics["fell"]
    assert np.linalg.norm(pos[-1, :2]) < 0.10
    assert abs(math.degrees(yaw[-1]) - 360.0) < 5.0
    _torques_within_limits(result)


SHORT_WALKS = """
version: 1
name: short-walks
gait: {period: 0.42, swing: 0.2}
tasks:
  - {action: walk, distance: [-0.098, -0.492], start: 0.1, duration: 1.76}
  - {action: walk, distance: [-0.544, 0.719], angle: -11.3, start: 1.86, duration: 3.37}
end: 6.23
"""


def test_a_walk_that_ends_short_stands_over_its_feet(tmp_path: Path) -> None:
    """Two back-to-back walks (envelope seed 16180, locomotion-000) end 12 cm short of the
    plan sideways, the feet 7 cm apart: the plan's CoM reference then lay 6 cm outside the
    outer foot, the MPC asked both feet for its least force and the robot sank and fell 0.4 s
    later. Standing, the reference is kept 2 cm inside the feet's support (`clamp_into_
    support`): the robot stays at its height over its feet to the end."""
    result = _run(tmp_path, SHORT_WALKS)
    t, pos, _ = _trajectory(result)
    assert not result.metrics["fell"]
    assert result.metrics["peak_torque_ratio"] <= 1.0
    after = t >= 5.3  # the second walk has ended
    assert np.max(np.abs(pos[after, 2] - NOMINAL_HEIGHT)) < 0.03
