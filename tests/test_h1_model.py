"""Unitree H1 description (robots/h1/): MuJoCo and pinocchio agree on it, and it stands.

The files are loaded directly (`mujoco.MjModel.from_xml_path`, `pin.buildModelFromMJCF`,
the YAML with ruamel), independently of locoplan's loader (written while the loader refused
H1's torso yaw; tests/test_robot_description.py checks what the loader builds now): this
test does the loader's cross-checks itself and uses only the pure convention maps of
`locoplan.robot.conventions`.

Free-flyer conventions as in tests/test_robot_dynamics.py: MuJoCo's qvel holds the pelvis'
linear velocity in WORLD axes, pinocchio's v in PELVIS axes; with
T = blkdiag(R_base_to_world^T, I3, I19), v_pin = T qvel, M_mj = T^T M_pin T,
J_mj = J_pin T, g_mj = T^T g_pin and qfrc_bias = T^T (nle + M_pin c), c = [-omega x v; 0].

Tolerance 1e-8 on dynamics terms, as for HECTOR: both libraries evaluate the same
rigid-body model in double precision (observed: 7e-14 on M, 4e-13 on bias and gravity,
1e-15 on site Jacobians; H1's terms are about 10x HECTOR's); a modelling or convention
error shows at 1e-3 and above.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from numpy.typing import NDArray
from ruamel.yaml import YAML

from locoplan.robot import conventions as cv

ROBOT_DIR = Path(__file__).resolve().parents[1] / "robots" / "h1"
MJCF = ROBOT_DIR / "h1.xml"
N_SAMPLES = 20
TOL = 1e-8  # see module docstring
# Sum of the published link masses (Unitree's URDF as carried by MuJoCo Menagerie
# unitree_h1, commit 83e4e86b): pelvis 5.39, torso 17.789, per leg 2.244 + 2.232 + 4.152 +
# 1.721 + 0.446, per arm 1.033 + 0.793 + 0.839 + 0.669. Unitree's product page: ~47 kg.
PUBLISHED_MASS = 51.437
N_JOINTS = 19

Array = NDArray[np.float64]


@pytest.fixture(scope="module")
def spec() -> dict[str, Any]:
    raw = YAML(typ="safe").load((ROBOT_DIR / "robot.yaml").read_text())
    assert isinstance(raw, dict)
    return raw


@pytest.fixture(scope="module")
def mj() -> tuple[mujoco.MjModel, mujoco.MjData]:
    model = mujoco.MjModel.from_xml_path(str(MJCF))
    return model, mujoco.MjData(model)


@pytest.fixture(scope="module")
def pinmodel() -> tuple[pin.Model, pin.Data]:
    model = pin.buildModelFromMJCF(str(MJCF))
    return model, model.createData()


def joint_names(spec: dict[str, Any]) -> list[str]:
    return [j["name"] for j in spec["joints"]]


def limits(spec: dict[str, Any]) -> tuple[Array, Array]:
    ranges = np.radians([j["range_deg"] for j in spec["joints"]])
    return ranges[:, 0], ranges[:, 1]


def site_names(spec: dict[str, Any]) -> list[str]:
    c = spec["contacts"]
    return [c["feet"]["L"], c["feet"]["R"], c["hands"]["L"], c["hands"]["R"], spec["imu_site"]]


def frame_id(model: pin.Model, name: str) -> int:
    """Pinocchio frame of an MJCF site (OP_FRAME) or body (BODY)."""
    for kind in (pin.FrameType.OP_FRAME, pin.FrameType.BODY):
        if model.existFrame(name, kind):
            return int(model.getFrameId(name, kind))
    raise KeyError(name)


def random_states(spec: dict[str, Any], n: int, seed: int) -> list[tuple[Array, Array]]:
    """n pinocchio states: random base pose and twist, joints uniform within their limits."""
    rng = np.random.default_rng(seed)
    lower, upper = limits(spec)
    states = []
    for _ in range(n):
        quat = rng.normal(size=4)
        quat /= np.linalg.norm(quat)
        q = np.concatenate(
            [rng.uniform([-1.0, -1.0, 0.5], [1.0, 1.0, 1.5]), quat, rng.uniform(lower, upper)]
        )
        v = np.concatenate(
            [rng.normal(0, 1.0, 3), rng.normal(0, 2.0, 3), rng.normal(0, 3.0, N_JOINTS)]
        )
        states.append((q, v))
    return states


def mj_forward(m: mujoco.MjModel, d: mujoco.MjData, q: Array, v: Array) -> None:
    d.qpos[:] = cv.pin_to_mj_q(q)
    d.qvel[:] = cv.pin_to_mj_v(q, v)
    d.qacc[:] = 0.0
    mujoco.mj_forward(m, d)


def nominal_q(spec: dict[str, Any], model: pin.Model) -> Array:
    q = pin.neutral(model)
    q[2] = spec["nominal"]["trunk_height"]
    deg = spec["nominal"]["joints_deg"]
    q[7:] = np.radians([deg[name] for name in joint_names(spec)])
    return np.asarray(q, dtype=np.float64)


# ---------------------------------------------------------------- description consistency
def test_yaml_matches_mjcf(spec: dict[str, Any], mj: tuple, pinmodel: tuple) -> None:
    """What locoplan's loader checks for HECTOR: joint and actuator order, ranges, torque
    limits, sites, keyframe; plus H1's joint groups (legs, arms, torso) and contact radii."""
    m, _ = mj
    names = joint_names(spec)
    assert len(names) == N_JOINTS
    assert (m.nq, m.nv, m.nu) == (7 + N_JOINTS, 6 + N_JOINTS, N_JOINTS)
    assert m.joint(0).name == "root" and m.body(m.jnt_bodyid[0]).name == spec["trunk_body"]
    assert [m.joint(j).name for j in range(1, m.njnt)] == names
    assert tuple(pinmodel[0].names) == ("universe", "root", *names)
    groups = [*spec["legs"]["L"], *spec["legs"]["R"], *spec["arms"]["L"], *spec["arms"]["R"]]
    groups += spec["torso"]
    assert sorted(groups) == sorted(names) and len(groups) == N_JOINTS
    assert len(spec["arms"]["L"]) == len(spec["arms"]["R"]) == 4

    lower, upper = limits(spec)
    hinges = [m.joint(n).id for n in names]
    assert m.jnt_limited[hinges].all()
    # 1e-7 rad: robot.yaml states the ranges to 1e-6 deg.
    assert np.abs(m.jnt_range[hinges] - np.column_stack([lower, upper])).max() < 1e-7
    torque = np.array([j["torque_Nm"] for j in spec["joints"]])
    assert [int(m.actuator_trnid[a, 0]) for a in range(m.nu)] == hinges
    assert np.allclose(m.actuator_gear[:, 0], 1.0) and m.actuator_ctrllimited.all()
    assert np.array_equal(m.actuator_ctrlrange, np.column_stack([-torque, torque]))
    for site in site_names(spec):
        assert m.site(site).bodyid >= 0

    key = m.key(spec["nominal_keyframe"])
    assert np.abs(key.qpos - cv.pin_to_mj_q(nominal_q(spec, pinmodel[0]))).max() < 1e-7

    radius = spec["contacts"]["hand_radius"]
    for side in "LR":
        assert m.geom(f"{side}_hand_sphere").size[0] == radius
        hand = m.site(spec["contacts"]["hands"][side])
        assert np.array_equal(m.geom(f"{side}_hand_sphere").pos, hand.pos)


def test_shoulder_axes_survive(pinmodel: tuple, mj: tuple) -> None:
    """The tilted shoulder-pitch hinges become RevoluteUnaligned joints in pinocchio."""
    model, _ = pinmodel
    for side, sign in (("L", 1.0), ("R", -1.0)):
        axis = model.joints[model.getJointId(f"{side}_shoulder_pitch")].extract().axis
        # R_x(+-0.43633 rad) (0, 1, 0): the published 25 deg shoulder tilt (URDF rpy).
        expected = [0.0, np.cos(0.43633), sign * np.sin(0.43633)]
        assert np.allclose(axis, expected, atol=1e-11)
        assert np.allclose(axis, mj[0].joint(f"{side}_shoulder_pitch").axis, atol=1e-12)


def test_total_mass(pinmodel: tuple, mj: tuple) -> None:
    # 1e-9 kg: a sum of 25 decimal masses, round-off is 1e-14.
    assert abs(float(np.sum(mj[0].body_mass)) - PUBLISHED_MASS) < 1e-9
    assert abs(pin.computeTotalMass(pinmodel[0]) - PUBLISHED_MASS) < 1e-9
    # Legs: 42 % of the mass (HECTOR's are 16 %); the paper's light-leg model does not hold.
    m = mj[0]
    links = ("hip_yaw_link", "hip_roll_link", "thigh", "calf", "foot")
    legs = sum(m.body_mass[m.body(f"{s}_{n}").id] for s in "LR" for n in links)
    assert abs(legs / PUBLISHED_MASS - 0.42) < 0.01


def test_armature_in_mass_matrix(pinmodel: tuple, mj: tuple) -> None:
    """pinocchio reads MJCF `armature` (the motors' reflected inertia) like MuJoCo."""
    assert np.array_equal(pinmodel[0].armature, mj[0].dof_armature)
    hip, knee, m40, m18 = 0.0633, 0.1605, 0.0102, 0.0036
    leg = [hip, hip, hip, knee, m40]
    arm = [m40, m40, m18, m18]
    assert np.array_equal(mj[0].dof_armature[6:], [*leg, *leg, hip, *arm, *arm])


# ---------------------------------------------------------------- dynamics agreement
def test_mass_matrix_bias_gravity(spec: dict[str, Any], pinmodel: tuple, mj: tuple) -> None:
    model, data = pinmodel
    m, d = mj
    M_mj = np.zeros((m.nv, m.nv))
    worst = 0.0
    for q, v in random_states(spec, N_SAMPLES, seed=3):
        pin.crba(model, data, q, pin.Convention.WORLD)
        M_pin = np.array(data.M)
        nle = np.array(pin.nonLinearEffects(model, data, q, v))
        g_pin = np.array(pin.computeGeneralizedGravity(model, data, q))
        mj_forward(m, d, q, v)
        mujoco.mj_fullM(m, d, M_mj)
        T = cv.velocity_transform(cv.pin_base_rotation(q), m.nv)
        errors = [
            np.abs(T.T @ M_pin @ T - M_mj).max(),
            np.abs(cv.pin_to_mj_mass_matrix(q, M_pin) - M_mj).max(),
            np.abs(cv.pin_to_mj_bias(q, v, M_pin, nle) - d.qfrc_bias).max(),
        ]
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
        errors.append(np.abs(cv.pin_to_mj_force(q, g_pin) - d.qfrc_bias).max())
        worst = max(worst, *errors)
    assert worst < TOL


def test_site_frames_and_jacobians(spec: dict[str, Any], pinmodel: tuple, mj: tuple) -> None:
    model, data = pinmodel
    m, d = mj
    jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    worst = 0.0
    for q, v in random_states(spec, N_SAMPLES, seed=5):
        pin.forwardKinematics(model, data, q, v)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        mj_forward(m, d, q, v)
        for name in site_names(spec):
            fid, sid = frame_id(model, name), m.site(name).id
            placement = data.oMf[fid]
            J_pin = pin.getFrameJacobian(model, data, fid, lwa)
            mujoco.mj_jacSite(m, d, jacp, jacr, sid)
            J_mj = cv.pin_to_mj_jacobian(q, J_pin)
            twist = pin.getFrameVelocity(model, data, fid, lwa).vector
            worst = max(
                worst,
                np.abs(placement.translation - d.site_xpos[sid]).max(),
                np.abs(placement.rotation - d.site_xmat[sid].reshape(3, 3)).max(),
                np.abs(J_mj - np.vstack([jacp, jacr])).max(),
                np.abs(twist - J_mj @ d.qvel).max(),
            )
    assert worst < TOL


# ---------------------------------------------------------------- nominal pose and stance
def test_nominal_pose_on_the_ground(spec: dict[str, Any], pinmodel: tuple, mj: tuple) -> None:
    """Soles flat on z = 0 in both models, the sole spheres touching, CoM mid-support."""
    model, data = pinmodel
    m, d = mj
    mujoco.mj_resetDataKeyframe(m, d, m.key(spec["nominal_keyframe"]).id)
    mujoco.mj_forward(m, d)
    q0 = nominal_q(spec, model)
    pin.framesForwardKinematics(model, data, q0)
    sphere = spec["contacts"]["foot_sphere_radius"]
    ankle_x = []
    for side in "LR":
        sole = spec["contacts"]["feet"][side]
        # 1e-6 m: the pose is stated to 1e-6 deg (< 1e-8 m at the sole).
        assert abs(d.site(sole).xpos[2]) < 1e-6
        assert np.abs(d.site(sole).xmat.reshape(3, 3) - np.eye(3)).max() < 1e-6
        assert np.abs(data.oMf[frame_id(model, sole)].translation - d.site(sole).xpos).max() < TOL
        for part, along in (("toe", spec["foot"]["toe"]), ("heel", -spec["foot"]["heel"])):
            geom = m.geom(f"{side}_foot_{part}")
            assert geom.size[0] == sphere
            bottom = d.geom(geom.id).xpos - [0.0, 0.0, sphere]
            assert np.abs(bottom - d.site(sole).xpos - [along, 0.0, 0.0]).max() < 1e-6
        assert abs(d.geom(f"{side}_foot_mid").xpos[2] - sphere) < 1e-6
        ankle_x.append(d.body(f"{side}_foot").xpos[0])
    assert abs(d.body(spec["trunk_body"]).xpos[2] - spec["nominal"]["trunk_height"]) < 1e-12
    com_ahead = d.subtree_com[m.body(spec["trunk_body"]).id][0] - np.mean(ankle_x)
    # Solved for mid-support, 0.0525 m ahead of the ankles (to 1e-5 m).
    assert abs(com_ahead - 0.5 * (spec["foot"]["toe"] - spec["foot"]["heel"])) < 1e-5
    assert 40.0 < spec["nominal"]["joints_deg"]["L_knee"] < 50.0
    for side in "LR":
        hand = d.site(spec["contacts"]["hands"][side]).xpos - d.body("pelvis").xpos
        assert 0.25 < hand[0] < 0.35
        shoulder = d.body(spec["reach"]["shoulders"][side]).xpos
        reach = np.linalg.norm(d.site(spec["contacts"]["hands"][side]).xpos - shoulder)
        assert abs(reach - spec["reach"]["nominal"]) < 1e-3


def test_joint_pd_stands_one_second(spec: dict[str, Any]) -> None:
    """A plain joint PD holding the keyframe keeps H1 standing on a floor for 1 s, gravity on.

    Gains: legs and torso 1500 N m/rad; ankles 1000 N m/rad, which must exceed half the
    whole-body pendulum stiffness m g h_com = 51.4 * 9.81 * 0.95 = 480 N m/rad per ankle
    (at 200 the robot topples forward); arms 200 / 50. Damping about critical for each
    joint's own inertia. No gravity feed-forward.
    """
    s = mujoco.MjSpec.from_file(str(MJCF))
    floor = s.worldbody.add_geom()
    floor.type = mujoco.mjtGeom.mjGEOM_PLANE
    floor.size = [5.0, 5.0, 0.1]
    m = s.compile()
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key(spec["nominal_keyframe"]).id)
    q_ref = d.qpos[7:].copy()
    p_ref = d.qpos[:3].copy()
    kp = np.array([1500.0] * 4 + [1000.0], dtype=np.float64)
    kd = np.array([40.0] * 4 + [30.0], dtype=np.float64)
    kp = np.concatenate([kp, kp, [1500.0], [200.0, 200.0, 50.0, 50.0] * 2])
    kd = np.concatenate([kd, kd, [40.0], [5.0, 5.0, 2.0, 2.0] * 2])
    limit = m.actuator_ctrlrange[:, 1]
    peak = 0.0
    soles = [m.site(spec["contacts"]["feet"][side]).id for side in "LR"]
    for _ in range(1000):
        tau = kp * (q_ref - d.qpos[7:]) - kd * d.qvel[6:]
        peak = max(peak, float(np.max(np.abs(tau) / limit)))
        d.ctrl[:] = np.clip(tau, -limit, limit)
        mujoco.mj_step(m, d)
        # The soles stay on the floor (contact penetration is about 1 mm).
        assert np.abs(d.site_xpos[soles, 2]).max() < 3e-3
    drift = d.qpos[:3] - p_ref
    assert abs(drift[2]) < 0.01  # sinks 5.5 mm (joint compliance and contact)
    assert np.hypot(drift[0], drift[1]) < 0.02  # sways within 7 mm
    tilt = np.degrees(np.arccos(np.clip(d.xmat[m.body("pelvis").id][8], -1.0, 1.0)))
    assert tilt < 2.0
    assert peak < 0.8  # peak |tau| / limit about 0.45 (knee and ankle), never clipped
