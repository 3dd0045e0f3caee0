"""PinocchioRobot against MuJoCo on the same MJCF, and the nominal pose's geometry.

Free-flyer velocity conventions differ between the two libraries: MuJoCo's qvel holds the
trunk's linear velocity in WORLD axes (angular in trunk axes), pinocchio's v holds both in
TRUNK axes, and the quaternions are (w, x, y, z) vs (x, y, z, w). With
T = blkdiag(R_base_to_world^T, I3, I16) we have v_pin = T qvel, so every comparison maps
pinocchio's quantities into MuJoCo's basis: M_mj = T^T M_pin T, J_mj = J_pin T,
g_mj = T^T g_pin and, because T itself rotates with the trunk,
qfrc_bias = T^T (nle + M_pin c) with c = [-omega x v_base; 0] (omega, v_base in trunk axes).
The states are drawn in pinocchio's convention and converted with
`locoplan.robot.conventions` before they are written into MjData.

Tolerances of 1e-8 on dynamics terms: both libraries evaluate the same rigid-body model in
double precision; the observed differences are 1e-13 to 1e-14, so 1e-8 catches any modelling
or convention error (those show up at 1e-3 and above) with a wide margin for round-off.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest
from numpy.typing import NDArray

from locoplan.exceptions import RobotDescriptionError
from locoplan.robot import conventions as cv
from locoplan.robot.description import RobotDescription, load_robot_description
from locoplan.robot.mujoco_model import load_mujoco_model, nominal_qpos
from locoplan.robot.pinocchio_model import PinocchioRobot

N_SAMPLES = 25
TOL = 1e-8  # see module docstring

Array = NDArray[np.float64]


@pytest.fixture(scope="module")
def desc() -> RobotDescription:
    return load_robot_description("hector")


@pytest.fixture(scope="module")
def robot(desc: RobotDescription) -> PinocchioRobot:
    return PinocchioRobot(desc)


@pytest.fixture(scope="module")
def mj(desc: RobotDescription) -> tuple[mujoco.MjModel, mujoco.MjData]:
    model = load_mujoco_model(desc)
    return model, mujoco.MjData(model)


def random_states(desc: RobotDescription, n: int, seed: int = 7) -> list[tuple[Array, Array]]:
    """n pinocchio states: random base pose and twist, joints uniform within their limits."""
    rng = np.random.default_rng(seed)
    states = []
    for _ in range(n):
        quat = rng.normal(size=4)
        quat /= np.linalg.norm(quat)
        q = np.concatenate(
            [
                rng.uniform([-1.0, -1.0, 0.2], [1.0, 1.0, 1.2]),
                quat,
                rng.uniform(desc.q_lower, desc.q_upper),
            ]
        )
        v = np.concatenate([rng.normal(0, 1.0, 3), rng.normal(0, 2.0, 3), rng.normal(0, 3.0, 16)])
        states.append((q, v))
    return states


def mj_forward(m: mujoco.MjModel, d: mujoco.MjData, q: Array, v: Array) -> None:
    d.qpos[:] = cv.pin_to_mj_q(q)
    d.qvel[:] = cv.pin_to_mj_v(q, v)
    d.qacc[:] = 0.0
    mujoco.mj_forward(m, d)


def test_dimensions_and_joint_order(desc: RobotDescription, robot: PinocchioRobot) -> None:
    assert (robot.nq, robot.nv) == (23, 22)
    assert tuple(robot.model.names) == ("universe", "root", *desc.joint_names)
    # The elbow axis (0, -1, 0) becomes a RevoluteUnaligned joint; check its axis survived.
    elbow = robot.model.joints[robot.model.getJointId("L_elbow")]
    assert np.allclose(elbow.extract().axis, [0.0, -1.0, 0.0])


def test_total_mass(desc: RobotDescription, robot: PinocchioRobot, mj: tuple) -> None:
    # 1e-9 kg: sums of 17 decimal masses, round-off is 1e-15.
    assert abs(desc.total_mass - 17.0) < 1e-9
    assert abs(robot.total_mass - 17.0) < 1e-9
    assert abs(float(np.sum(mj[0].body_mass)) - 17.0) < 1e-9


def test_armature_in_mass_matrix(robot: PinocchioRobot, mj: tuple) -> None:
    """pin 4.1 reads MJCF `armature` into model.armature and crba adds it to M's diagonal."""
    assert np.allclose(robot.model.armature, mj[0].dof_armature, atol=0, rtol=0)
    assert np.allclose(robot.model.armature[6:], [0.01, 0.01, 0.01, 0.04, 0.01] * 2 + [0.01] * 6)


def test_mass_matrix_bias_gravity(desc: RobotDescription, robot: PinocchioRobot, mj: tuple) -> None:
    m, d = mj
    M_mj = np.zeros((m.nv, m.nv))
    for q, v in random_states(desc, N_SAMPLES):
        robot.update(q, v)
        mj_forward(m, d, q, v)
        mujoco.mj_fullM(m, d, M_mj)
        R = cv.pin_base_rotation(q)
        T = cv.velocity_transform(R, robot.nv)
        M_pin = robot.M
        assert np.allclose(M_pin, M_pin.T, atol=0, rtol=0)
        assert np.abs(T.T @ M_pin @ T - M_mj).max() < TOL
        assert np.abs(cv.pin_to_mj_mass_matrix(q, M_pin) - M_mj).max() < TOL
        assert np.abs(cv.pin_to_mj_bias(q, v, M_pin, robot.h) - d.qfrc_bias).max() < TOL
        # Gravity alone: MuJoCo's bias forces at zero velocity.
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
        assert np.abs(T.T @ robot.gravity(q) - d.qfrc_bias).max() < TOL
        assert np.abs(cv.pin_to_mj_force(q, robot.gravity(q)) - d.qfrc_bias).max() < TOL


def test_frames_and_jacobians(desc: RobotDescription, robot: PinocchioRobot, mj: tuple) -> None:
    m, d = mj
    jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    sites = (*desc.foot_frames, *desc.hand_frames, desc.imu_site)
    for q, v in random_states(desc, N_SAMPLES, seed=11):
        robot.update(q, v)
        mj_forward(m, d, q, v)
        qvel = d.qvel.copy()
        for name in sites:
            sid = m.site(name).id
            assert np.abs(robot.frame_position(name) - d.site_xpos[sid]).max() < TOL
            R_mj = d.site_xmat[sid].reshape(3, 3)
            assert np.abs(robot.frame_rotation(name) - R_mj).max() < TOL
            mujoco.mj_jacSite(m, d, jacp, jacr, sid)
            J_mj = cv.pin_to_mj_jacobian(q, robot.frame_jacobian(name))
            assert np.abs(J_mj - np.vstack([jacp, jacr])).max() < TOL
            # Same twist from either velocity vector.
            assert np.abs(robot.frame_velocity(name) - J_mj @ qvel).max() < TOL
        pose = robot.base_pose()
        assert np.abs(pose.p_world - d.xpos[m.body(desc.trunk_body).id]).max() < TOL
        assert np.abs(pose.R_to_world - cv.pin_base_rotation(q)).max() < TOL


def test_jdot_v_matches_mujoco_jacdot(
    desc: RobotDescription, robot: PinocchioRobot, mj: tuple
) -> None:
    """frame_jdot_v equals MuJoCo's mj_jacDot after the basis change.

    J_mj = J_pin T, so d/dt(J_mj) qvel = Jdot_pin v + J_pin c with c = Tdot qvel =
    [-omega x v_base; 0]; hence Jdot_pin v = Jdot_mj qvel - J_pin c.
    """
    m, d = mj
    jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    for q, v in random_states(desc, N_SAMPLES, seed=13):
        robot.update(q, v)
        mj_forward(m, d, q, v)
        for name in (*desc.foot_frames, *desc.hand_frames):
            sid = m.site(name).id
            mujoco.mj_jacDot(m, d, jacp, jacr, d.site_xpos[sid], m.site_bodyid[sid])
            jdot_v_mj = np.vstack([jacp, jacr]) @ d.qvel
            expected = jdot_v_mj - robot.frame_jacobian(name) @ cv.basis_change_drift(v)
            assert np.abs(robot.frame_jdot_v(name) - expected).max() < TOL


def test_jdot_v_finite_differences(desc: RobotDescription, robot: PinocchioRobot) -> None:
    """Jdot v against central differences of J(q(t)) v along q(t) = q (+) t v (a = 0).

    Step h = 2e-6 s balances truncation, h^2/6 |d3x/dt3| (|d3x/dt3| ~ 1e4 at these
    random joint rates of up to ~10 rad/s: ~7e-9), against round-off, eps |J v| / h
    (~2e-16 * 30 / 2e-6 = 3e-9); the largest error seen is 5e-9. The 1e-6 tolerance keeps a
    200x margin, while a wrong drift (a missing Coriolis term, the spatial instead of the
    classical acceleration) is O(|v|^2 L) ~ 1 m/s^2.
    """
    h = 2e-6
    aux = PinocchioRobot(desc)
    for q, v in random_states(desc, N_SAMPLES, seed=17):
        robot.update(q, v)
        for name in (*desc.foot_frames, *desc.hand_frames, desc.base_frame):
            xdot = []
            for t in (-h, h):
                aux.update(pin.integrate(robot.model, q, t * v), v)
                xdot.append(aux.frame_jacobian(name) @ v)
            fd = (xdot[1] - xdot[0]) / (2 * h)
            assert np.abs(robot.frame_jdot_v(name) - fd).max() < 1e-6


def test_com_and_composite_inertia(
    desc: RobotDescription, robot: PinocchioRobot, mj: tuple
) -> None:
    m, d = mj
    trunk = m.body(desc.trunk_body).id
    for q, v in random_states(desc, N_SAMPLES, seed=19):
        robot.update(q, v)
        mj_forward(m, d, q, v)
        mujoco.mj_subtreeVel(m, d)
        com = d.subtree_com[trunk]
        assert np.abs(robot.com_position - com).max() < TOL
        assert np.abs(robot.com_velocity - d.subtree_linvel[trunk]).max() < TOL
        # Composite inertia about the CoM from MuJoCo's body inertias (parallel axis theorem).
        I_world = np.zeros((3, 3))
        for b in range(1, m.nbody):
            R = d.ximat[b].reshape(3, 3)
            r = d.xipos[b] - com
            I_world += R @ np.diag(m.body_inertia[b]) @ R.T
            I_world += m.body_mass[b] * (r @ r * np.eye(3) - np.outer(r, r))
        assert np.abs(robot.composite_inertia_world() - I_world).max() < TOL
        # ... which is the angular block of pinocchio's centroidal inertia.
        data = robot.model.createData()
        pin.ccrba(robot.model, data, q, v)
        assert np.abs(robot.composite_inertia_world() - data.Ig.inertia).max() < TOL
    # Nominal pose: the composite pitch inertia is well above the trunk's 0.15 kg m^2.
    robot.update(robot.nominal_q(), np.zeros(robot.nv))
    assert 0.3 < robot.composite_inertia_world()[1, 1] < 0.9


def test_update_is_idempotent_and_gravity_pure(
    desc: RobotDescription, robot: PinocchioRobot
) -> None:
    (q, v), (q2, _) = random_states(desc, 2, seed=23)
    robot.update(q, v)
    before = (robot.M, robot.h, robot.frame_jacobian("L_sole"), robot.frame_jdot_v("R_hand"))
    robot.gravity(q2)  # uses its own pinocchio Data
    after = (robot.M, robot.h, robot.frame_jacobian("L_sole"), robot.frame_jdot_v("R_hand"))
    for x, y in zip(before, after, strict=True):
        assert np.array_equal(x, y)
    with pytest.raises(KeyError, match="no frame"):
        robot.frame_id("L_toe_tip")


def test_nominal_pose(desc: RobotDescription, robot: PinocchioRobot, mj: tuple) -> None:
    """Soles flat on z = 0, CoM over the middle of the line feet, hands ready to carry."""
    m, _ = mj
    q0 = robot.nominal_q()
    assert np.allclose(cv.pin_to_mj_q(q0), nominal_qpos(desc, m), atol=1e-7, rtol=0)
    robot.update(q0, np.zeros(robot.nv))
    for sole in desc.foot_frames:
        # 1e-6 m: the pose is stated to 1e-6 deg (< 1e-8 m at the sole).
        assert abs(robot.frame_position(sole)[2]) < 1e-6
        assert np.abs(robot.frame_rotation(sole) - np.eye(3)).max() < 1e-6
    ankles_x = [robot.frame_position(f.replace("sole", "foot"))[0] for f in desc.foot_frames]
    com_ahead = robot.com_position[0] - np.mean(ankles_x)
    assert -desc.foot_heel < com_ahead < desc.foot_toe
    # The pose was solved for mid-support, 0.015 m ahead of the ankles (to 1e-5 m).
    assert abs(com_ahead - 0.5 * (desc.foot_toe - desc.foot_heel)) < 1e-5
    assert abs(robot.base_pose().p_world[2] - desc.base_height_nominal) < 1e-12
    assert 60.0 < np.degrees(desc.q_joints_nominal[desc.joint_names.index("L_knee")]) < 70.0
    p_base = robot.base_pose().p_world
    for hand, side in zip(desc.hand_frames, (1.0, -1.0), strict=True):
        p = robot.frame_position(hand) - p_base
        assert 0.25 <= p[0] <= 0.30
        assert abs(p[1] - side * 0.12) < 1e-9
        assert abs(p[2] + 0.05) < 0.01


@pytest.mark.parametrize(
    ("joint", "angle", "frame", "direction"),
    [
        ("L_elbow", 0.3, "L_hand", (1, 0, 1)),  # flexion: hand forward and up
        ("R_elbow", 0.3, "R_hand", (1, 0, 1)),
        ("L_shoulder_pitch", -0.3, "L_hand", (1, 0, 1)),  # negative lifts the arm forward
        ("L_shoulder_roll", 0.3, "L_hand", (0, 1, 1)),  # left arm outward (+y)
        ("R_shoulder_roll", 0.3, "R_hand", (0, 1, 1)),  # right arm inward (+y)
        ("R_shoulder_roll", -0.3, "R_hand", (0, -1, 1)),  # right arm outward
        ("L_knee", 0.3, "L_sole", (-1, 0, 1)),  # flexion: foot backward and up
        ("R_hip_pitch", 0.3, "R_sole", (-1, 0, 1)),  # positive swings the leg back
        ("L_hip_roll", 0.3, "L_sole", (0, 1, 1)),  # about +x: foot toward +y
    ],
)
def test_sign_conventions(
    desc: RobotDescription, joint: str, angle: float, frame: str, direction: tuple
) -> None:
    """Joint signs as documented, from the straight pose (all joints 0, trunk at the origin).

    This also checks that pinocchio reads the elbow's (0, -1, 0) axis with its sign.
    """
    robot = PinocchioRobot(desc)
    q = pin.neutral(robot.model)
    robot.update(q, np.zeros(robot.nv))
    p0 = robot.frame_position(frame)
    q[7 + desc.joint_names.index(joint)] = angle
    robot.update(q, np.zeros(robot.nv))
    dp = robot.frame_position(frame) - p0
    for axis, sign in enumerate(direction):
        if sign == 0:
            assert abs(dp[axis]) < 1e-12  # a planar motion: round-off only
        else:
            assert np.sign(dp[axis]) == sign and abs(dp[axis]) > 1e-3


def test_frames_kinematics_stacks_the_single_frame_accessors(
    desc: RobotDescription, robot: PinocchioRobot
) -> None:
    names = (*desc.foot_frames, *desc.hand_frames, desc.trunk_body)
    for q, v in random_states(desc, 3, seed=5):
        robot.update(q, v)
        p, R, J, dJv = robot.frames_kinematics(names)
        for i, name in enumerate(names):
            # Same pinocchio data read two ways: equal to the last bit.
            assert np.array_equal(p[i], robot.frame_position(name))
            assert np.array_equal(R[i], robot.frame_rotation(name))
            assert np.array_equal(J[i], robot.frame_jacobian(name))
            assert np.array_equal(dJv[i], robot.frame_jdot_v(name))


def test_partial_inertia_and_joint_axes() -> None:
    """`inertia_without_joints_world` with no joint left out is the composite inertia; a
    hinge's axis is a unit vector in the world (HECTOR's and H1's ankles: +y at the nominal
    pose, 1e-12: round-off of the kinematics). Unknown joints raise."""
    for name in ("hector", "h1"):
        d = load_robot_description(name)
        r = PinocchioRobot(d)
        assert np.allclose(r.inertia_without_joints_world(()), r.composite_inertia_world())
        for leg in d.leg_joint_indices:
            _, axis = r.joint_axis_world(d.joint_names[int(leg[-1])])
            assert np.allclose(axis, [0.0, 1.0, 0.0], atol=1e-12)
        with pytest.raises(RobotDescriptionError):
            r.joint_axis_world("tail")
        with pytest.raises(RobotDescriptionError):
            r.inertia_without_joints_world(("tail",))
