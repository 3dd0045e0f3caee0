"""The Foxglove 3D scene the closed loop logs (`locoplan.render.view_log`): robot geometry on
the link frames of /tf lands where MuJoCo has the geoms, objects, fixtures, footholds, contact
arrows, the MPC prediction, torque ratios and the /sim/qpos samples, read back from the MCAP
file as Foxglove would."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import pytest

from locoplan.log.reader import RunLog, read_log
from locoplan.log.writer import RunLogWriter
from locoplan.plan import Plan, compile_plan
from locoplan.render.samples import RenderSample
from locoplan.render.view_log import SCENE_MPC, SCENE_ROBOT, TORQUE_RATIO, robot_geometry
from locoplan.robot.description import load_robot_description
from locoplan.scenario import load_scenario_file
from locoplan.sim.loop import ClosedLoop
from locoplan.sim.run import RunOptions, controller_settings, scene_for
from locoplan.sim.scene import Scene

pytestmark = pytest.mark.closed_loop

ROOT = Path(__file__).resolve().parents[1]
T_END = 0.6  # s: long enough for the scene grid (1/30 s) and the first MPC solutions
# /tf and the scene's world poses come from MjData.xpos / geom_xpos, which mj_step computes
# before it integrates qpos: they lag the logged qpos by one 1 ms step, |v| dt < 1 mm for
# link speeds below 1 m/s.
LAG_TOL = 1e-3  # m


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Scene, Plan, RunLog]:
    loaded = load_scenario_file(ROOT / "scenarios" / "pick-walk-drop.yaml")
    scenario = loaded.scenario
    desc = load_robot_description(scenario.robot)
    scene = scene_for(scenario, desc)
    plan = compile_plan(scenario)
    path = tmp_path_factory.mktemp("scene3d") / "run.mcap"
    with RunLogWriter(path, scenario_name=scenario.name, scenario_text=loaded.text) as log:
        loop = ClosedLoop(
            scene,
            desc,
            plan,
            controller_settings(scenario, RunOptions()),
            start_yaw=math.radians(scenario.robot_start.yaw),
            log=log,
        )
        loop.run(T_END)
    return scene, plan, read_log(path)


def _quat_xyzw_to_mat(q: Any) -> np.ndarray:
    R = np.empty(9)
    mujoco.mju_quat2Mat(R, np.array([q.w, q.x, q.y, q.z]))
    return R.reshape(3, 3)


def _vec(v: Any) -> np.ndarray:
    return np.array([v.x, v.y, v.z])


def test_robot_geometry_sits_on_the_links_where_mujoco_has_the_geoms(
    run: tuple[Scene, Plan, RunLog],
) -> None:
    scene, _, log = run
    m = scene.model
    tf = {t: msg for t, msg in log.messages("/tf")}
    samples = {t: RenderSample.from_payload(t, p) for t, p in log.messages("/sim/qpos")}
    updates = list(log.messages(SCENE_ROBOT))
    # Re-published on the 1/30 s grid (entities are not frame-locked in the SDK): one update
    # per grid time up to the last sample (0.591 s).
    assert log.end_time is not None
    assert len(updates) == math.floor(log.end_time * 30) + 1
    t, update = updates[len(updates) // 2]
    frames = {tr.child_frame_id: tr for tr in tf[t].transforms}
    data = mujoco.MjData(m)
    data.qpos[:] = samples[t].qpos
    mujoco.mj_kinematics(m, data)
    checked = 0
    for entity in update.entities:
        assert entity.frame_id in frames, entity.frame_id  # every link frame is in /tf
        link = frames[entity.frame_id]
        R_link, p_link = _quat_xyzw_to_mat(link.rotation), _vec(link.translation)
        for cube in entity.cubes:
            body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, entity.frame_id)
            p_world = p_link + R_link @ _vec(cube.pose.position)
            # The logged box pose composed with /tf is where MuJoCo has one of its geoms.
            gids = range(m.body_geomadr[body], m.body_geomadr[body] + m.body_geomnum[body])
            assert min(np.linalg.norm(data.geom_xpos[g] - p_world) for g in gids) < LAG_TOL
            checked += 1
        for line in entity.lines:
            a, b = (p_link + R_link @ _vec(p) for p in line.points)
            centre = (a + b) / 2
            gap = min(np.linalg.norm(data.geom_xpos[g] - centre) for g in range(m.ngeom))
            assert gap < LAG_TOL
            checked += 1
    assert checked >= 10
    # Every visible robot geom is drawn: boxes, spheres, capsules (segment + two caps).
    items = robot_geometry(scene)
    assert sum(len(e.cubes) + len(e.spheres) + len(e.lines) for e in update.entities) == len(items)


def test_objects_fixtures_and_footholds(run: tuple[Scene, Plan, RunLog]) -> None:
    scene, plan, log = run
    fixtures = list(log.messages("/scene/fixtures"))
    assert len(fixtures) == 1 and fixtures[0][0] == 0.0  # static: once, at t = 0
    sizes = {e.id: _vec(e.cubes[0].size) for e in fixtures[0][1].entities}
    assert np.allclose(sizes["fixture/table"], [0.50, 0.40, 0.47])
    assert np.allclose(sizes["fixture/platform"], [0.40, 0.50, 0.47])
    footholds = list(log.messages("/scene/footholds"))
    assert len(footholds) == 1
    n_planned = sum(len(p) for p in plan.footholds.positions)
    assert len(footholds[0][1].entities) == n_planned
    box_id = scene.object_body_ids["box"]
    for _, update in log.messages("/scene/objects"):
        (entity,) = update.entities
        assert entity.frame_id == "world"
        assert np.allclose(_vec(entity.cubes[0].size), [0.20, 0.20, 0.15])
    # The last object pose is the box's body position at that time (one geom at its centre).
    m = scene.model
    data = mujoco.MjData(m)
    t_last, _ = list(log.messages("/scene/objects"))[-1]
    data.qpos[:] = dict(log.messages("/sim/qpos"))[t_last]["qpos"]
    mujoco.mj_kinematics(m, data)
    assert np.allclose(_vec(entity.cubes[0].pose.position), data.xpos[box_id], atol=LAG_TOL)


def test_contact_arrows_follow_the_measured_forces(run: tuple[Scene, Plan, RunLog]) -> None:
    _, _, log = run
    measured = dict(log.messages("/contact/measured"))
    n_arrows = 0
    for t, update in log.messages("/scene/contacts"):
        if t == 0.0:
            continue  # before the first step nothing has been measured
        forces = np.asarray(measured[t]["force_world"])
        for entity in update.entities:
            (arrow,) = entity.arrows
            k = "LR".index(entity.id[-1])
            length = arrow.shaft_length + arrow.head_length
            # 2 mm per N (locoplan.log.scene.force_arrow).
            assert length == pytest.approx(0.002 * np.linalg.norm(forces[k]), rel=1e-9)
            n_arrows += 1
    # Standing on both feet for the first 0.5 s: both soles carry load at every grid time.
    assert n_arrows >= 2 * (len(measured) // 4)


def test_mpc_prediction_torque_ratio_and_samples(run: tuple[Scene, Plan, RunLog]) -> None:
    scene, _, log = run
    strips = [u for _, u in log.messages(SCENE_MPC) if u.entities]
    assert strips, "no MPC prediction drawn"
    points = np.array([_vec(p) for p in strips[-1].entities[0].lines[0].points])
    # The predicted CoM stays near the standing trunk height over the horizon.
    assert points.shape[0] >= 5 and np.all(np.abs(points[:, 2] - 0.55) < 0.15)
    limits = dict(zip(scene.robot.joint_names, scene.robot.torque_limits, strict=True))
    efforts = {t: msg for t, msg in log.messages("/joint_states")}
    for t, ratio in log.messages(TORQUE_RATIO):
        assert all(-1.0 - 1e-9 <= r <= 1.0 + 1e-9 for r in ratio.values())
        if t in efforts:
            for joint in efforts[t].joints:
                assert ratio[joint.name] == pytest.approx(joint.effort / limits[joint.name])
    # /sim/qpos: the first sample is the state before the first tick, then one per 10 ms.
    times = [t for t, _ in log.messages("/sim/qpos")]
    assert times[0] == 0.0 and len(times) == round(T_END / 0.01) + 1
    assert np.all(np.diff(times) > 0)


def _layout_paths(node: Any) -> list[str]:
    """Every message path ("value" of plot/state series, "topicPath") and 3D topic of a
    Foxglove layout's panel configs."""
    paths: list[str] = []
    if isinstance(node, dict):
        for key, value in node.items():
            if key in ("value", "topicPath") and isinstance(value, str):
                paths.append(value)
            elif key == "topics" and isinstance(value, dict):
                paths += list(value)
            else:
                paths += _layout_paths(value)
    elif isinstance(node, list):
        for item in node:
            paths += _layout_paths(item)
    return paths


def test_foxglove_layout_refers_to_what_the_log_holds(run: tuple[Scene, Plan, RunLog]) -> None:
    scene, _, log = run
    layout = json.loads((ROOT / "docs" / "foxglove-layout.json").read_text())
    panels = {key.split("!")[0] for key in layout["configById"]}
    assert {"3D", "Plot", "StateTransitions"} <= panels
    ratio = next(iter(log.messages(TORQUE_RATIO)))[1]
    sample = next(iter(log.messages("/sim/qpos")))[1]
    paths = _layout_paths(layout["configById"])
    assert paths
    for path in paths:
        topic = re.match(r"/[^.\[{]+", path)
        assert topic is not None and topic.group(0) in log.topics, path
        field = path[topic.end() :].lstrip(".")
        if topic.group(0) == TORQUE_RATIO:
            assert field in ratio, path
        elif topic.group(0) == "/sim/qpos":
            assert field.split("[")[0] in sample, path
    # Every joint's torque ratio is plotted.
    plotted = {p.split(".")[-1] for p in paths if p.startswith(TORQUE_RATIO)}
    assert plotted == set(scene.robot.joint_names)
