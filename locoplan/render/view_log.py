"""What the closed loop writes so that a person can see a run in Foxglove (and re-render it).

Topics (all at simulation time, scene topics as foxglove.SceneUpdate, the rest JSON):
- ``/sim/qpos`` every recorded sample: the scene's full qpos, stance flags and task label
  (`locoplan.render.samples`); ``locoplan render`` rebuilds the video from it;
- ``/robot/torque_ratio`` every recorded sample: tau / torque limit per joint (signed, so the
  limits are +-1 on a plot);
- ``/scene/robot``: the robot's geoms, each attached to its link's frame from ``/tf`` (boxes,
  spheres; capsules and cylinders as thick line segments, capsules with sphere caps), so
  Foxglove draws the robot without a URDF;
- ``/scene/objects``: the scenario's objects where they are (world frame);
- ``/scene/fixtures`` and ``/scene/footholds``: the static scenery and every planned foothold,
  once at t = 0;
- ``/scene/contacts``: measured ground reaction forces as arrows at the soles (2 mm per N);
- ``/scene/mpc``: the MPC's predicted CoM trajectory over its horizon as a line strip.

Foxglove resolves a scene entity's frame at the entity's timestamp and keeps it there (the
SDK's entities are not frame-locked), so the moving topics are re-published on a fixed grid,
`scene_period` (default 1/30 s, the video's rate); the robot's entities are encoded once
(`locoplan.log.scene.prepare_scene`) and only re-stamped, and what the other moving entities
take from the model (ids, sizes, colours, sites) is looked up once per run (`ObjectItems`,
`ViewLogger`). Measured cost on this machine: see `ViewLogger.sample`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np
import numpy.typing as npt

from locoplan.log import topics
from locoplan.log.scene import (
    Box,
    Rgba,
    SceneItem,
    Sphere,
    box,
    force_arrow,
    line_strip,
    prepare_scene,
    sphere,
)
from locoplan.log.writer import RunLogWriter
from locoplan.plan import Plan
from locoplan.render.samples import SAMPLE_TOPIC, RenderSample, to_ns
from locoplan.sim.scene import Scene

FloatArray = npt.NDArray[np.float64]

SCENE_ROBOT = "/scene/robot"
SCENE_MPC = "/scene/mpc"
TORQUE_RATIO = "/robot/torque_ratio"
VISIBLE_GROUPS = 3  # MuJoCo draws geom groups 0..2 by default; group 3+ is hidden detail
CONTACT_MIN_N = 1.0  # N: below this a foot is not drawn as carrying load
FOOTHOLD_WIDTH = 0.05  # m, drawn foothold width (the sole is a line of three spheres)
FOOTHOLD_THICKNESS = 0.002  # m
FOOT_COLORS = (Rgba(0.2, 0.75, 0.3, 0.6), Rgba(0.2, 0.4, 0.9, 0.6))  # left green, right blue
MPC_COLOR = Rgba(0.85, 0.1, 0.6, 1.0)
FIXTURE_COLOR = Rgba(0.55, 0.4, 0.25, 1.0)

# MuJoCo's geom types as plain ints: looking up an `mjtGeom` member and comparing with it costs
# about a microsecond, an int comparison a few tens of nanoseconds.
_BOX = int(mujoco.mjtGeom.mjGEOM_BOX)
_SPHERE = int(mujoco.mjtGeom.mjGEOM_SPHERE)
_ELLIPSOID = int(mujoco.mjtGeom.mjGEOM_ELLIPSOID)
_CAPSULE = int(mujoco.mjtGeom.mjGEOM_CAPSULE)
_CYLINDER = int(mujoco.mjtGeom.mjGEOM_CYLINDER)


def _xyzw(quat_wxyz: npt.ArrayLike) -> tuple[float, float, float, float]:
    w, x, y, z = (float(v) for v in np.asarray(quat_wxyz, dtype=float))
    return (x, y, z, w)


def _rgba(m: mujoco.MjModel, g: int) -> Rgba:
    mat = int(m.geom_matid[g])
    rgba = m.mat_rgba[mat] if mat >= 0 else m.geom_rgba[g]
    return Rgba(*(min(1.0, max(0.0, float(c))) for c in rgba))


def geom_items(
    m: mujoco.MjModel,
    g: int,
    entity_id: str,
    position: FloatArray,
    quat_wxyz: FloatArray,
    frame_id: str,
) -> list[SceneItem]:
    """Scene items drawing geom `g` at `position` (3,) / `quat_wxyz` (4,) in `frame_id`.

    Boxes and spheres map one to one; a capsule is a line segment of its diameter with a
    sphere at each end, a cylinder the segment alone, an ellipsoid a sphere of its largest
    radius. Planes, meshes and other types give no item (none in the robot files we ship).
    """
    size = m.geom_size[g]
    color = _rgba(m, g)
    gtype = int(m.geom_type[g])
    if gtype == _BOX:
        return [
            box(
                entity_id,
                position,
                2.0 * size,
                orientation=_xyzw(quat_wxyz),
                color=color,
                frame_id=frame_id,
            )
        ]
    if gtype == _SPHERE:
        return [sphere(entity_id, position, 2.0 * size[0], color=color, frame_id=frame_id)]
    if gtype == _ELLIPSOID:
        return [sphere(entity_id, position, 2.0 * max(size), color=color, frame_id=frame_id)]
    if gtype in (_CAPSULE, _CYLINDER):
        R = np.empty(9)
        mujoco.mju_quat2Mat(R, np.asarray(quat_wxyz, dtype=float))
        half = R.reshape(3, 3)[:, 2] * size[1]
        ends = np.stack([position - half, position + half])
        items: list[SceneItem] = [
            line_strip(entity_id, ends, thickness=2.0 * size[0], color=color, frame_id=frame_id)
        ]
        if gtype == _CAPSULE:
            for k, end in enumerate(ends):
                items.append(
                    sphere(
                        f"{entity_id}/cap{k}", end, 2.0 * size[0], color=color, frame_id=frame_id
                    )
                )
        return items
    return []


def robot_geometry(scene: Scene) -> list[SceneItem]:
    """Every visible robot geom as scene items in its link's frame (the ``/tf`` child frame
    named after the MuJoCo body), poses relative to the link (`geom_pos`, `geom_quat`)."""
    m = scene.model
    object_bodies = set(scene.object_body_ids.values())
    items: list[SceneItem] = []
    for g in range(m.ngeom):
        b = int(m.geom_bodyid[g])
        if b == 0 or b in object_bodies or int(m.geom_group[g]) >= VISIBLE_GROUPS:
            continue
        body = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}"
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom{g}"
        items += geom_items(
            m,
            g,
            f"robot/{body}/{name}",
            np.asarray(m.geom_pos[g], dtype=float),
            np.asarray(m.geom_quat[g], dtype=float),
            body,
        )
    return items


def fixture_items(scene: Scene) -> list[SceneItem]:
    """The static world geoms the scenario added (fixtures), world frame."""
    m = scene.model
    items: list[SceneItem] = []
    for name, g in scene.fixture_geom_ids.items():
        items += geom_items(
            m,
            g,
            f"fixture/{name}",
            np.asarray(m.geom_pos[g], dtype=float),
            np.asarray(m.geom_quat[g], dtype=float),
            "world",
        )
    return items


def object_items(scene: Scene, data: mujoco.MjData) -> list[SceneItem]:
    """The scenario's objects at their current poses (world frame). Called once per sample,
    a `ViewLogger` keeps an `ObjectItems` instead."""
    return ObjectItems(scene)(data)


class ObjectItems:
    """`object_items` of one scene, with what is constant over a run worked out once.

    A geom's id, entity id, type, size and colour (`body_geomadr`, `body_geomnum`,
    `geom_type`, `geom_size`, `geom_matid`, `mat_rgba`, `geom_rgba`) are MjModel fields nothing
    changes after the scene is compiled, so per call only the pose is read from MjData. The
    constant parts are those of the item `geom_items` makes for the geom at the origin (a
    box's size and colour, a sphere's diameter and colour): both paths give the same items to
    the bit. Geoms that are not one box or sphere item (capsules, cylinders; none among the
    scenario shapes) go through `geom_items` at every call. A box object costs about 2 us
    instead of 9 us through `geom_items` (hot caches, measured on this machine).
    """

    def __init__(self, scene: Scene) -> None:
        m = scene.model
        self._model = m
        self._quat = np.empty(4)  # mju_mat2Quat's output, read before the next geom's call
        # (geom id, entity id, the item at the origin or None: geom_items at every call)
        geoms: list[tuple[int, str, Box | Sphere | None]] = []
        origin, identity = np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0])
        for name, b in scene.object_body_ids.items():
            first, count = int(m.body_geomadr[b]), int(m.body_geomnum[b])
            for g in range(first, first + count):
                entity_id = f"object/{name}/{g}"
                items = geom_items(m, g, entity_id, origin, identity, "world")
                proto = items[0] if len(items) == 1 else None
                geoms.append((g, entity_id, proto if isinstance(proto, Box | Sphere) else None))
        self._geoms = tuple(geoms)

    def __call__(self, data: mujoco.MjData) -> list[SceneItem]:
        """The objects' items at the poses in `data` (world frame)."""
        xpos, xmat, quat = data.geom_xpos, data.geom_xmat, self._quat
        items: list[SceneItem] = []
        for g, entity_id, proto in self._geoms:
            if isinstance(proto, Sphere):  # no orientation
                px, py, pz = xpos[g].tolist()
                items.append(Sphere(entity_id, (px, py, pz), proto.diameter, proto.color, "world"))
                continue
            mujoco.mju_mat2Quat(quat, xmat[g])
            if isinstance(proto, Box):
                px, py, pz = xpos[g].tolist()
                w, x, y, z = quat.tolist()
                items.append(
                    Box(entity_id, (px, py, pz), proto.size, (x, y, z, w), proto.color, "world")
                )
            else:
                items += geom_items(self._model, g, entity_id, np.asarray(xpos[g]), quat, "world")
        return items


def foothold_items(plan: Plan, foot_length: float) -> list[SceneItem]:
    """Every planned foothold of both feet as a thin box on the floor (world frame)."""
    items: list[SceneItem] = []
    for f, foot in enumerate(("L", "R")):
        positions = plan.footholds.positions[f]
        yaws = plan.footholds.yaws[f]
        for i, (p, yaw) in enumerate(zip(positions, yaws, strict=True)):
            items.append(
                box(
                    f"foothold/{foot}/{i}",
                    (float(p[0]), float(p[1]), FOOTHOLD_THICKNESS / 2),
                    (foot_length, FOOTHOLD_WIDTH, FOOTHOLD_THICKNESS),
                    orientation=(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)),
                    color=FOOT_COLORS[f],
                )
            )
    return items


class ViewLogger:
    """Writes the samples and the 3D scene of one run to its log (see the module docstring).

    `start` once before the first tick, `sample` at every recorded sample (any rate; the
    scene topics are thinned to `scene_period`).
    """

    def __init__(
        self,
        scene: Scene,
        plan: Plan,
        log: RunLogWriter,
        scene_period: float = 1.0 / 30.0,
    ) -> None:
        if not scene_period > 0.0:
            raise ValueError(f"scene_period must be positive, got {scene_period}")
        self.scene = scene
        self.plan = plan
        self.log = log
        m = scene.model
        desc = scene.robot
        self._period_ns = to_ns(scene_period)
        self._next_scene_ns = 0
        # Constant in the links' frames: encoded once, only re-stamped on the scene grid.
        self._robot = prepare_scene(robot_geometry(scene))
        self._joint_names = list(desc.joint_names)
        self._inv_limits = 1.0 / np.asarray(desc.torque_limits, dtype=float)
        self._objects = ObjectItems(scene)
        # Per foot: sole site id (constant in the compiled model), arrow entity id, colour.
        self._feet = tuple(
            (mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, name), f"contact/{side}", color)
            for name, side, color in zip(desc.foot_frames, "LR", FOOT_COLORS, strict=True)
        )
        self._foot_length = desc.foot_toe + desc.foot_heel
        self._com_prediction: FloatArray | None = None

    def start(self, sample: RenderSample, data: mujoco.MjData) -> None:
        """Static scenery (fixtures, footholds) and the first sample, at the sample's time."""
        t = sample.t
        self.log.scene(topics.SCENE_FIXTURES, t, fixture_items(self.scene))
        self.log.scene(topics.SCENE_FOOTHOLDS, t, foothold_items(self.plan, self._foot_length))
        self.sample(sample, data, np.zeros((2, 3)), None, np.zeros(len(self._joint_names)))

    def sample(
        self,
        sample: RenderSample,
        data: mujoco.MjData,
        f_contact_world: FloatArray,
        com_prediction: FloatArray | None,
        tau: FloatArray,
    ) -> None:
        """Log one sample: ``/sim/qpos`` and ``/robot/torque_ratio`` always, the scene topics
        when the scene grid is due.

        `data` holds the state of `sample`; `f_contact_world` (2, 3) N the measured ground
        reaction per foot; `com_prediction` (n, 3) m the MPC's predicted CoM path when the
        MPC ran at this tick (the last one is kept otherwise); `tau` (n_joints,) N m the
        applied torques. Costs about 35 us per call on average in the closed loop (package
        transfer, measured on this machine): about 24 us off the scene grid, about 60 us on
        it (48, 24 and 104 us when every grid call looked the objects' and feet's constants up
        in the model). These means include the writer's batch encoding of every queued
        message, run when one of the call's messages fills its queue (`RunLogWriter._emit`);
        without it the medians are about 13 us off the grid and 60 us on it.
        """
        t = sample.t
        log = self.log
        log.json(SAMPLE_TOPIC, t, sample.to_payload())
        ratio = np.asarray(tau, dtype=float) * self._inv_limits
        log.json(TORQUE_RATIO, t, dict(zip(self._joint_names, ratio.tolist(), strict=True)))
        if com_prediction is not None:
            self._com_prediction = np.asarray(com_prediction, dtype=float)
        t_ns = sample.t_ns
        if t_ns < self._next_scene_ns:
            return
        while self._next_scene_ns <= t_ns:
            self._next_scene_ns += self._period_ns
        log.scene(SCENE_ROBOT, t, self._robot)
        log.scene(topics.SCENE_OBJECTS, t, self._objects(data))
        log.scene(topics.SCENE_CONTACTS, t, self._contact_items(data, f_contact_world))
        log.scene(SCENE_MPC, t, self._mpc_items())

    def _contact_items(self, data: mujoco.MjData, f_contact_world: FloatArray) -> list[SceneItem]:
        """A `force_arrow` per foot carrying at least `CONTACT_MIN_N`, at its sole site."""
        site_xpos = data.site_xpos
        items: list[SceneItem] = []
        for (site, entity_id, color), f in zip(self._feet, f_contact_world, strict=True):
            if float(np.linalg.norm(f)) < CONTACT_MIN_N:
                continue
            items.append(force_arrow(entity_id, site_xpos[site], f, color=color))
        return items

    def _mpc_items(self) -> list[SceneItem]:
        """The last MPC prediction as a line strip (none before the first prediction or for
        one of fewer than two points)."""
        path = self._com_prediction
        if path is None or len(path) < 2:
            return []
        return [line_strip("mpc/com", path, color=MPC_COLOR)]


def sample_from_data(
    t: float, data: mujoco.MjData, stance: Sequence[bool], task: str
) -> RenderSample:
    """A `RenderSample` of the current `data` (qpos copied)."""
    qpos = np.asarray(data.qpos, dtype=float).copy()
    return RenderSample(t, qpos, (bool(stance[0]), bool(stance[1])), task)
