"""MuJoCo model of the robot: index maps, keyframe, contacts, and the joint-PD stand.

The stand test is the bring-up's model sanity check: the nominal keyframe on a floor built
through MjSpec rests on all six sole spheres, and a joint PD holding the keyframe keeps the
trunk within 1 cm of its height for 2 s.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from locoplan.exceptions import RobotDescriptionError
from locoplan.robot.description import RobotDescription, load_robot_description
from locoplan.robot.mujoco_model import (
    actuator_indices,
    joint_qpos_indices,
    joint_qvel_indices,
    load_mujoco_model,
    load_mujoco_spec,
    nominal_qpos,
    robot_qpos_indices,
    robot_qvel_indices,
    root_qpos_indices,
    root_qvel_indices,
)

SOLE_SPHERES = [f"{s}_foot_{p}" for s in "LR" for p in ("toe", "mid", "heel")]


@pytest.fixture(scope="module")
def desc() -> RobotDescription:
    return load_robot_description("hector")


def scene_with_floor(desc: RobotDescription, with_box: bool = False) -> mujoco.MjModel:
    """The robot plus a floor plane (friction 1.0), and optionally a free box, via MjSpec."""
    spec = load_mujoco_spec(desc)
    spec.worldbody.add_geom(
        name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[5, 5, 0.1], friction=[1, 0.005, 1e-4]
    )
    if with_box:
        box = spec.worldbody.add_body(name="box", pos=[0.4, 0.0, 0.1])
        box.add_freejoint(name="box_root")
        box.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.1, 0.1, 0.1], mass=2.0)
    return spec.compile()


def test_model_options(desc: RobotDescription) -> None:
    m = load_mujoco_model(desc)
    assert m.opt.timestep == 0.001
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    assert m.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    assert m.opt.impratio == 10.0
    assert (m.nq, m.nv, m.nu) == (23, 22, 16)
    assert np.all(m.actuator_ctrllimited)
    assert np.allclose(m.actuator_ctrlrange[:, 1], desc.torque_limits)
    # Every body renders: each has at least one geom; every moving body has mass.
    assert np.all(m.body_geomnum[1:] >= 1)
    assert np.all(m.body_mass[1:] > 0) and np.all(m.body_inertia[1:] > 0)
    assert np.all((m.dof_damping[6:] >= 0.1) & (m.dof_damping[6:] <= 0.3))


def test_index_maps_on_extended_model(desc: RobotDescription) -> None:
    m = scene_with_floor(desc, with_box=True)
    assert m.nq == 30
    assert np.array_equal(joint_qpos_indices(desc, m), np.arange(7, 23))
    assert np.array_equal(joint_qvel_indices(desc, m), np.arange(6, 22))
    assert np.array_equal(root_qpos_indices(desc, m), np.arange(0, 7))
    assert np.array_equal(root_qvel_indices(desc, m), np.arange(0, 6))
    assert np.array_equal(robot_qpos_indices(desc, m), np.arange(23))
    assert np.array_equal(robot_qvel_indices(desc, m), np.arange(22))
    assert np.array_equal(actuator_indices(desc, m), np.arange(16))
    names = [m.actuator(int(a)).name for a in actuator_indices(desc, m)]
    assert names == list(desc.joint_names)
    # The keyframe of the extended model keeps the robot pose; the box sits at its qpos0.
    qpos = nominal_qpos(desc, m)
    assert qpos.shape == (30,)
    assert np.allclose(qpos[23:26], [0.4, 0.0, 0.1])


def test_added_elements_keep_mujoco_defaults(desc: RobotDescription) -> None:
    """Robot defaults live in class "hector": MjSpec additions collide and have no armature."""
    m = scene_with_floor(desc, with_box=True)
    floor = m.geom("floor")
    assert (int(floor.contype[0]), int(floor.conaffinity[0])) == (1, 1)
    box_dofs = slice(22, 28)
    assert np.all(m.dof_armature[box_dofs] == 0) and np.all(m.dof_damping[box_dofs] == 0)


def test_collision_filter(desc: RobotDescription) -> None:
    """Only sole and hand spheres collide, with the environment only, never with each other."""
    m = load_mujoco_model(desc)
    colliding = [
        m.geom(g).name for g in range(m.ngeom) if m.geom_contype[g] or m.geom_conaffinity[g]
    ]
    assert sorted(colliding) == sorted([*SOLE_SPHERES, "L_hand_sphere", "R_hand_sphere"])
    for g in colliding:
        for h in colliding:
            a, b = m.geom(g), m.geom(h)
            assert not (a.contype[0] & b.conaffinity[0] or b.contype[0] & a.conaffinity[0])
    # Sphere bottoms on the sole plane 0.04 m below the ankle, toe +0.09, heel -0.06.
    for side in "LR":
        for part, x in (("toe", 0.09), ("heel", -0.06)):
            g = m.geom(f"{side}_foot_{part}")
            assert np.allclose(g.pos, [x, 0.0, -0.04 + g.size[0]])
        assert np.allclose(m.site(f"{side}_sole").pos, [0.0, 0.0, -0.04])


def test_hands_collide_with_objects(desc: RobotDescription) -> None:
    m = scene_with_floor(desc, with_box=True)
    d = mujoco.MjData(m)
    d.qpos[:] = nominal_qpos(desc, m)
    mujoco.mj_forward(m, d)
    # Put the box where the left hand sphere is, overlapping it by 5 mm.
    box_adr = int(m.jnt_qposadr[m.joint("box_root").id])
    hand = d.geom("L_hand_sphere")
    d.qpos[box_adr : box_adr + 3] = hand.xpos + np.array([0.1 + 0.02 - 0.005, 0.0, 0.0])
    mujoco.mj_forward(m, d)
    pairs = {
        frozenset((m.geom(int(c.geom1)).name, m.geom(int(c.geom2)).name))
        for c in d.contact[: d.ncon]
    }
    assert any("L_hand_sphere" in p for p in pairs)


def test_nominal_qpos_rejects_other_keyframes(desc: RobotDescription) -> None:
    spec = load_mujoco_spec(desc)
    spec.key("stand").qpos[9] += 0.01  # L_hip_pitch
    with pytest.raises(RobotDescriptionError, match="differs"):
        nominal_qpos(desc, spec.compile())


def test_joint_pd_holds_keyframe(desc: RobotDescription) -> None:
    """Keyframe on a floor: rests on all six sole spheres; a joint PD stands 2 s (< 1 cm)."""
    m = scene_with_floor(desc)
    d = mujoco.MjData(m)
    q_ref = nominal_qpos(desc, m)
    d.qpos[:] = q_ref
    mujoco.mj_forward(m, d)
    qadr, vadr = joint_qpos_indices(desc, m), joint_qvel_indices(desc, m)
    act = actuator_indices(desc, m)
    # Stiff enough that the steady-state sag (knee torque ~9 N m / 400) stays ~4 mm.
    kp = np.where(np.isin(np.arange(16), np.concatenate(desc.leg_joint_indices)), 400.0, 100.0)
    kd = 0.05 * kp
    z0 = d.qpos[2]
    floor = m.geom("floor").id
    heights, min_contacts = [], 6
    for step in range(2000):
        d.ctrl[act] = kp * (q_ref[qadr] - d.qpos[qadr]) - kd * d.qvel[vadr]
        mujoco.mj_step(m, d)
        heights.append(d.qpos[2])
        if step >= 200:  # after the initial contact transient
            touching = {
                m.geom(int(c.geom1 if c.geom2 == floor else c.geom2)).name
                for c in d.contact[: d.ncon]
                if floor in (c.geom1, c.geom2)
            }
            min_contacts = min(min_contacts, len(touching & set(SOLE_SPHERES)))
    assert min_contacts == 6
    assert np.max(np.abs(np.array(heights) - z0)) < 0.01
    # Upright: the PD's compliance (knee sag ~1.3 deg under ~9 N m at kp 400) tilts the
    # trunk by ~1.0 deg; 2 deg leaves margin and still catches a model that leans or slides.
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, d.qpos[3:7])
    assert R[8] > np.cos(np.radians(2.0))
    assert np.max(np.abs(d.qpos[0:2] - q_ref[0:2])) < 0.02
