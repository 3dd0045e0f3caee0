"""`locoplan.render.view_log`'s per-sample scene items (objects, contact arrows, the MPC's CoM
path) are those of the generic constructors (`geom_items`, `force_arrow`, `line_strip`)
value for value: the precomputed paths change the cost, not the log. No simulation step."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import mujoco
import numpy as np
import pytest

from locoplan.log.scene import SceneItem, force_arrow, line_strip
from locoplan.log.writer import RunLogWriter
from locoplan.plan import compile_plan
from locoplan.render.view_log import (
    CONTACT_MIN_N,
    FOOT_COLORS,
    MPC_COLOR,
    ObjectItems,
    ViewLogger,
    geom_items,
    object_items,
)
from locoplan.robot.description import load_robot_description
from locoplan.scenario import load_scenario_file
from locoplan.sim.run import scene_for
from locoplan.sim.scene import ObjectDef, Scene, build_scene

ROOT = Path(__file__).resolve().parents[1]


def _reference_object_items(scene: Scene, data: mujoco.MjData) -> list[SceneItem]:
    """The objects' items as `geom_items` makes them for every geom at its current pose."""
    m = scene.model
    items: list[SceneItem] = []
    quat = np.empty(4)
    for name, b in scene.object_body_ids.items():
        first, count = int(m.body_geomadr[b]), int(m.body_geomnum[b])
        for g in range(first, first + count):
            mujoco.mju_mat2Quat(quat, data.geom_xmat[g])
            items += geom_items(
                m, g, f"object/{name}/{g}", np.asarray(data.geom_xpos[g]), quat, "world"
            )
    return items


def test_object_items_are_those_of_geom_items_at_random_poses() -> None:
    loaded = load_scenario_file(ROOT / "scenarios" / "package-transfer.yaml")
    desc = load_robot_description(loaded.scenario.robot)
    objects = (
        ObjectDef("crate", "box", (0.3, 0.2, 0.25), 2.0, (0.5, 0.0, 0.4), yaw=0.3),
        ObjectDef("ball", "sphere", (0.1,), 1.0, (0.2, 0.4, 0.6)),
    )
    scene = build_scene(desc, objects)
    m, d = scene.model, mujoco.MjData(scene.model)
    fast = ObjectItems(scene)
    rng = np.random.default_rng(7)
    for _ in range(20):
        for b in scene.object_body_ids.values():
            adr = int(m.jnt_qposadr[m.body_jntadr[b]])
            quat = rng.normal(size=4)
            d.qpos[adr : adr + 7] = np.concatenate(
                [rng.uniform(-2, 2, 3), quat / np.linalg.norm(quat)]
            )
        mujoco.mj_kinematics(m, d)
        reference = _reference_object_items(scene, d)
        assert len(reference) == 2
        assert fast(d) == reference
        assert object_items(scene, d) == reference


@pytest.fixture()
def view(tmp_path: Path) -> Iterator[tuple[ViewLogger, mujoco.MjData]]:
    loaded = load_scenario_file(ROOT / "scenarios" / "throw.yaml")
    desc = load_robot_description(loaded.scenario.robot)
    scene = scene_for(loaded.scenario, desc)
    data = mujoco.MjData(scene.model)
    mujoco.mj_kinematics(scene.model, data)
    with RunLogWriter(
        tmp_path / "run.mcap", scenario_name="throw", scenario_text=loaded.text
    ) as log:
        yield ViewLogger(scene, compile_plan(loaded.scenario), log), data


def test_contact_arrows_are_those_of_force_arrow(view: tuple[ViewLogger, mujoco.MjData]) -> None:
    logger, data = view
    desc = logger.scene.robot
    sites = [
        mujoco.mj_name2id(logger.scene.model, mujoco.mjtObj.mjOBJ_SITE, s) for s in desc.foot_frames
    ]
    rng = np.random.default_rng(3)
    # Loads either side of the threshold, one foot unloaded, a non-contiguous array.
    cases = [rng.normal(scale=s, size=(2, 3)) for s in (0.3, 0.6, 1.0, 50.0)]
    cases += [np.array([[0.0, 0.0, 0.0], [3.0, -2.0, 85.0]]), np.arange(12.0).reshape(2, 6)[:, ::2]]
    for forces in cases:
        reference = [
            force_arrow(f"contact/{'LR'[k]}", data.site_xpos[site], f, color=FOOT_COLORS[k])
            for k, (site, f) in enumerate(zip(sites, forces, strict=True))
            if float(np.linalg.norm(f)) >= CONTACT_MIN_N
        ]
        assert logger._contact_items(data, forces) == reference


def test_mpc_path_is_that_of_line_strip(view: tuple[ViewLogger, mujoco.MjData]) -> None:
    logger, _ = view
    assert logger._mpc_items() == []
    X = np.random.default_rng(5).normal(size=(21, 13))
    logger._com_prediction = np.asarray(X[:, 3:6], dtype=float)  # as the loop passes it
    assert logger._mpc_items() == [line_strip("mpc/com", X[:, 3:6], color=MPC_COLOR)]
    logger._com_prediction = X[:1, 3:6]
    assert logger._mpc_items() == []
