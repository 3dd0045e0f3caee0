"""Tests of locoplan.sim.backend on the real scene: the state handed to the controller, the
finite-state check and the measured foot forces (checked against MuJoCo's own
`mj_contactForce`, one contact at a time, for both friction cone types)."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from locoplan.robot import conventions as cv
from locoplan.robot.description import load_robot_description
from locoplan.scenario import load_scenario_file
from locoplan.sim.backend import MujocoBackend
from locoplan.sim.run import scene_for
from locoplan.sim.scene import Scene

ROOT = Path(__file__).resolve().parents[1]


def _scene() -> Scene:
    scenario = load_scenario_file(ROOT / "scenarios" / "stand.yaml").scenario
    return scene_for(scenario, load_robot_description(scenario.robot))


def _reference_foot_forces(be: MujocoBackend, feet: list[int]) -> np.ndarray:
    """The contact loop with mj_contactForce per contact (what the kernel replaces)."""
    m, d = be.model, be.data
    out = np.zeros((2, 3))
    wrench = np.zeros(6)
    for i in range(d.ncon):
        c = d.contact[i]
        b1, b2 = m.geom_bodyid[c.geom1], m.geom_bodyid[c.geom2]
        for k, fb in enumerate(feet):
            if fb not in (b1, b2):
                continue
            mujoco.mj_contactForce(m, d, i, wrench)
            f_world = c.frame.reshape(3, 3).T @ wrench[:3]
            out[k] += f_world if fb == b2 else -f_world
    return out


@pytest.mark.parametrize("cone", [mujoco.mjtCone.mjCONE_ELLIPTIC, mujoco.mjtCone.mjCONE_PYRAMIDAL])
def test_foot_forces_match_mj_contact_force(cone: mujoco.mjtCone) -> None:
    scene = _scene()
    scene.model.opt.cone = cone
    be = MujocoBackend(scene)
    be.reset()
    feet = [
        int(scene.model.site_bodyid[mujoco.mj_name2id(scene.model, mujoco.mjtObj.mjOBJ_SITE, s)])
        for s in scene.robot.foot_frames
    ]
    rng = np.random.default_rng(0)
    checked = 0
    for k in range(400):
        be.step(rng.normal(size=16) * 2.0)  # stumbling about: contacts come and go
        if k % 10:
            continue
        got = be.foot_contact_forces()
        want = _reference_foot_forces(be, feet)
        # 1e-9 N: the same products summed in another order differ by a few ulps of ~100 N.
        assert np.allclose(got, want, rtol=0.0, atol=1e-9)
        checked += int(np.abs(want).sum() > 1.0)
    assert checked > 10  # the feet did carry load in most of the samples


def test_robot_state_and_finite_check() -> None:
    be = MujocoBackend(_scene())
    be.reset((0.3, -0.2), 0.7)
    for _ in range(5):
        be.step(np.zeros(16))
    state = be.robot_state()
    d = be.data
    assert state.t == d.time
    # Bit for bit the conventions' conversions (the controller must see the same numbers).
    assert np.array_equal(state.q, cv.mj_to_pin_q(d.qpos[:23]))
    assert np.array_equal(state.v, cv.mj_to_pin_v(d.qpos[:23], d.qvel[:22]))
    assert be.state_is_finite()
    d.qvel[4] = np.nan
    assert not be.state_is_finite()
    d.qvel[4] = 0.0
    d.qpos[9] = -np.inf
    assert not be.state_is_finite()
    d.qpos[9] = 1e308
    assert be.state_is_finite()
