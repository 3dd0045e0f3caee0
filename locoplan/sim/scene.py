"""MuJoCo scene: the robot's MJCF plus a floor, and the scenario's objects and fixtures.

The robot file stays the single source of truth (pinocchio loads the same file); the scene
only adds the world around it through `mujoco.MjSpec`. Objects become free bodies with
collisions; fixtures are static boxes whose top surface is at `size[2]`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np
import numpy.typing as npt

from locoplan.robot.description import RobotDescription
from locoplan.robot.mujoco_model import load_mujoco_spec

FloatArray = npt.NDArray[np.float64]

FLOOR_FRICTION = 1.0
FIXTURE_FRICTION = 1.0
OBJECT_FRICTION = 1.0
BELT_CONTACT_FRICTION = 0.05


@dataclass(frozen=True, slots=True)
class ObjectDef:
    """A movable object: `size` is full extents (box) or [radius] (sphere); SI units."""

    name: str
    shape: str
    size: tuple[float, ...]
    mass: float
    position: tuple[float, float, float]
    yaw: float = 0.0


@dataclass(frozen=True, slots=True)
class FixtureDef:
    """Static scenery: `position` is the footprint centre on the floor, `size` full extents."""

    name: str
    kind: str
    position: tuple[float, float, float]
    size: tuple[float, float, float]
    yaw: float = 0.0
    speed: float = 0.0


@dataclass(slots=True)
class Scene:
    """A compiled MuJoCo scene with the ids the simulator needs."""

    model: mujoco.MjModel
    robot: RobotDescription
    object_body_ids: dict[str, int] = field(default_factory=dict)
    object_geom_ids: dict[str, int] = field(default_factory=dict)
    object_defs: dict[str, ObjectDef] = field(default_factory=dict)
    fixture_geom_ids: dict[str, int] = field(default_factory=dict)
    fixture_defs: dict[str, FixtureDef] = field(default_factory=dict)
    # Inactive weld equality ids per (object, hand index 0=L/1=R): the grasp mechanism.
    grasp_welds: dict[tuple[str, int], int] = field(default_factory=dict)
    hand_body_ids: tuple[int, ...] = ()
    floor_geom_id: int = -1


def _yaw_quat(yaw: float) -> list[float]:
    return [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]


def build_scene(
    robot: RobotDescription,
    objects: tuple[ObjectDef, ...] = (),
    fixtures: tuple[FixtureDef, ...] = (),
    timestep: float = 0.001,
) -> Scene:
    """Compile robot + floor + objects + fixtures into one MjModel (physics step `timestep` s)."""
    spec = load_mujoco_spec(robot)
    spec.option.timestep = timestep
    world = spec.worldbody
    world.add_light(
        name="sun",
        pos=[0.0, 0.0, 3.0],
        dir=[0.0, 0.0, -1.0],
        type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
    )
    world.add_geom(
        name="floor",
        type=mujoco.mjtGeom.mjGEOM_PLANE,
        size=[20.0, 20.0, 0.1],
        friction=[FLOOR_FRICTION, 0.005, 0.0001],
        rgba=[0.8, 0.8, 0.8, 1.0],
        contype=1,
        conaffinity=1,
    )
    for fx in fixtures:
        sx, sy, sz = fx.size
        world.add_geom(
            name=f"fixture_{fx.name}",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[sx / 2, sy / 2, sz / 2],
            pos=[fx.position[0], fx.position[1], fx.position[2] + sz / 2],
            quat=_yaw_quat(fx.yaw),
            # A conveyor's top is a moving belt: its contact friction is near zero and the belt's
            # drag (locoplan.sim.grasp.ConveyorDrive) moves what rests on it.
            friction=[
                FIXTURE_FRICTION if fx.kind != "conveyor" else BELT_CONTACT_FRICTION,
                0.005,
                0.0001,
            ],
            # MuJoCo takes the larger friction of two geoms unless one has priority.
            priority=1 if fx.kind == "conveyor" else 0,
            rgba=[0.55, 0.4, 0.25, 1.0] if fx.kind != "conveyor" else [0.2, 0.2, 0.25, 1.0],
            contype=1,
            conaffinity=1,
        )
    for ob in objects:
        body = world.add_body(
            name=f"object_{ob.name}", pos=list(ob.position), quat=_yaw_quat(ob.yaw)
        )
        body.add_freejoint(name=f"object_{ob.name}_free")
        if ob.shape == "box":
            gtype, gsize = mujoco.mjtGeom.mjGEOM_BOX, [s / 2 for s in ob.size]
        else:
            gtype, gsize = mujoco.mjtGeom.mjGEOM_SPHERE, [ob.size[0], 0.0, 0.0]
        body.add_geom(
            name=f"object_{ob.name}_geom",
            type=gtype,
            size=gsize,
            mass=ob.mass,
            friction=[OBJECT_FRICTION, 0.005, 0.0001],
            rgba=[0.85, 0.6, 0.2, 1.0],
            contype=1,
            conaffinity=1,
        )
    hand_bodies = [spec.site(site).parent.name for site in robot.hand_frames]
    for ob in objects:
        for k, hand_body in enumerate(hand_bodies):
            # Grasp = a point connection between the hand and the object, switched on by the
            # simulator when the hand touches the object at the planned grasp time (see
            # locoplan.sim.grasp); its anchors are set at that instant so nothing jumps.
            spec.add_equality(
                name=f"grasp_{ob.name}_{k}",
                type=mujoco.mjtEq.mjEQ_CONNECT,
                objtype=mujoco.mjtObj.mjOBJ_BODY,
                name1=hand_body,
                name2=f"object_{ob.name}",
                active=False,
            )
    model = spec.compile()
    scene = Scene(model=model, robot=robot)
    scene.hand_body_ids = tuple(
        mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, b) for b in hand_bodies
    )
    scene.floor_geom_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    for ob in objects:
        scene.object_body_ids[ob.name] = mujoco.mj_name2id(
            model, mujoco.mjtObj.mjOBJ_BODY, f"object_{ob.name}"
        )
        scene.object_geom_ids[ob.name] = mujoco.mj_name2id(
            model, mujoco.mjtObj.mjOBJ_GEOM, f"object_{ob.name}_geom"
        )
        scene.object_defs[ob.name] = ob
        for k in range(len(hand_bodies)):
            scene.grasp_welds[(ob.name, k)] = mujoco.mj_name2id(
                model, mujoco.mjtObj.mjOBJ_EQUALITY, f"grasp_{ob.name}_{k}"
            )
    for fx in fixtures:
        scene.fixture_geom_ids[fx.name] = mujoco.mj_name2id(
            model, mujoco.mjtObj.mjOBJ_GEOM, f"fixture_{fx.name}"
        )
        scene.fixture_defs[fx.name] = fx
    return scene
