"""locoplan.control.lean: the trunk's lean for a held load, against the statics it is derived
from (pinocchio gravity torques of the robot pitched back), and the WBC's pitch target."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from plan_fixtures import hold_script, scenario_from_text
from scipy.spatial.transform import Rotation

from locoplan.control.controller import (
    LEAN_RATE,
    LOAD_LEAD,
    ControllerSettings,
    LocoManipulationController,
)
from locoplan.control.lean import LEAN_MAX, TrunkLean
from locoplan.control.wbc_kernels import yaw_error, yaw_pitch_error
from locoplan.plan import compile_plan
from locoplan.robot.description import load_robot_description
from locoplan.robot.pinocchio_model import PinocchioRobot

GRAVITY = 9.81


@pytest.fixture(scope="module", params=["hector", "h1"])
def robot(request: pytest.FixtureRequest) -> PinocchioRobot:
    return PinocchioRobot(load_robot_description(request.param))


def _hip_moment(robot: PinocchioRobot, lean: float, mass: float, ahead: float) -> float:
    """Moment (N m) about the hips' mean pitch axis of the gravity on every body the legs do
    not move and of `mass` kg at `ahead` m in front of the trunk origin (at its height), with
    the trunk pitched back by `lean` about its origin: summed over the bodies directly
    (pinocchio's forward kinematics), not through TrunkLean's formula."""
    model, desc = robot.model, robot.desc
    data = model.createData()
    q = robot.nominal_q()
    q[3:7] = Rotation.from_euler("y", -lean).as_quat()  # x, y, z, w: nose up
    pin.forwardKinematics(model, data, q)
    legs = {
        model.getJointId(desc.joint_names[int(j)]) for leg in desc.leg_joint_indices for j in leg
    }
    hips = [
        np.asarray(data.oMi[model.getJointId(desc.joint_names[j])].translation)
        for j in robot.hip_pitch_joints()
    ]
    x_hip = float(np.mean(hips, axis=0)[0])
    moment = mass * GRAVITY * (q[0] + ahead - x_hip)
    for j in range(1, model.njoints):
        if j not in legs:
            body = data.oMi[j].act(model.inertias[j])
            moment += body.mass * GRAVITY * (float(body.lever[0]) - x_hip)
    return moment


def test_no_load_no_lean(robot: PinocchioRobot) -> None:
    lean = TrunkLean(robot)
    got = lean.angles(np.array([0.0, 0.0, 3.0]), np.array([0.3, -0.2, -0.2]))
    # No mass, or a load behind the point the upper body balances over: upright.
    np.testing.assert_array_equal(got, 0.0)


def test_lean_cancels_the_loads_hip_moment(robot: PinocchioRobot) -> None:
    """At the lean, the upper body and the load weigh on the hips as the unloaded upper body
    does upright (the module's defining equation), summed body by body; 1e-6 N m: the
    bisection's 30 halvings of LEAN_MAX leave 4e-10 rad."""
    lean = TrunkLean(robot)
    unloaded = _hip_moment(robot, 0.0, 0.0, 0.0)
    for mass, ahead in ((1.0, 0.2), (3.0, 0.25), (2.0, 0.3)):
        b = float(lean.angles(np.array([mass]), np.array([ahead]))[0])
        assert 0.0 < b < LEAN_MAX
        assert _hip_moment(robot, b, mass, ahead) == pytest.approx(unloaded, abs=1e-6)
        # Upright, the load adds its weight times its distance ahead of the hips.
        assert _hip_moment(robot, 0.0, mass, ahead) > unloaded + 0.5 * mass * GRAVITY * ahead


def test_lean_grows_with_the_load_and_stops_at_its_bound(robot: PinocchioRobot) -> None:
    lean = TrunkLean(robot)
    masses = np.linspace(0.5, 60.0, 40)
    got = lean.angles(masses, np.full_like(masses, 0.3))
    assert np.all(np.diff(got) >= 0.0)
    assert got[-1] == LEAN_MAX
    # Beyond the bound the load keeps part of its moment: more lean would still reduce it.
    assert _hip_moment(robot, LEAN_MAX, 60.0, 0.3) > _hip_moment(robot, 0.0, 0.0, 0.0)


def test_hector_leans_about_the_labs_three_degrees_per_kg() -> None:
    """shared/robot.md: the lab's MPC leans HECTOR about 3 deg per kg held in front. Here the
    lean comes from the masses; at the carry-in distance (0.2 m) it is 2.5-4.5 deg per kg
    over the envelope's 1-5 kg (the upper body's moment about the hips grows with sin b)."""
    lean = TrunkLean(PinocchioRobot(load_robot_description("hector")))
    masses = np.array([1.0, 3.0, 5.0])
    per_kg = np.degrees(lean.angles(masses, np.full(3, 0.2))) / masses
    assert np.all((per_kg > 2.5) & (per_kg < 4.5))


def test_yaw_pitch_error_is_the_rotation_to_the_target() -> None:
    rng = np.random.default_rng(3)
    for _ in range(20):
        yaw, pitch = rng.uniform(-math.pi, math.pi), rng.uniform(-0.6, 0.6)
        R = Rotation.from_rotvec(rng.normal(scale=0.4, size=3)).as_matrix()
        e = np.array(yaw_pitch_error(yaw, pitch, R))
        target = Rotation.from_euler("ZY", [yaw, pitch]).as_matrix()
        # exp([e]x) R = R_z(yaw) R_y(pitch), to rounding.
        np.testing.assert_allclose(Rotation.from_rotvec(e).as_matrix() @ R, target, atol=1e-12)
        assert yaw_pitch_error(yaw, 0.0, R) == pytest.approx(yaw_error(yaw, R), abs=1e-15)


def _controller(trunk_lean: bool = True) -> LocoManipulationController:
    desc = load_robot_description("hector")
    plan = compile_plan(scenario_from_text(hold_script(5.0)))
    return LocoManipulationController(
        PinocchioRobot(desc), desc, plan, ControllerSettings(trunk_lean=trunk_lean)
    )


def test_controller_lean_follows_the_load_no_faster_than_its_rate() -> None:
    """The lean the controller commands (`_lean_limited` on the `_lean` targets) at every
    10 ms update through the hold: zero before the load, never changing by more than
    LEAN_RATE per second, the static lean of the measured load (the planned object's offset
    from the trunk) once it has had time to get there, and back to zero after the release."""
    ctl = _controller()
    (hold,) = ctl.plan.holds
    dt = ctl.s.mpc.dt
    leans = []
    times = np.round(np.arange(0.0, ctl.plan.t_end, 0.01), 9)
    for t in times:
        t_lead = t + dt * np.arange(0, ctl.s.mpc.horizon + 1) + LOAD_LEAD
        ctl._update_load(float(t), hold.mass * 9.81 if hold.lift <= t < hold.release else 0.0)
        mass = ctl.shift_mass(t_lead)
        _, _, yaw, _, pb = ctl._com_reference(t_lead)
        lean = ctl._lean_limited(float(t), dt, ctl._lean(float(t), t_lead, mass, pb, yaw))
        ctl._lean_now = float(lean[0])
        assert np.all(np.abs(np.diff(lean)) <= LEAN_RATE * dt + 1e-12)
        leans.append(ctl._lean_now)
    leans_a = np.array(leans)
    assert np.all(np.abs(np.diff(leans_a)) <= LEAN_RATE * 0.01 + 1e-12)
    assert np.all(leans_a[times < hold.lift - LOAD_LEAD - 0.3] == 0.0)
    settled = float(leans_a[np.searchsorted(times, hold.release - 0.5)])
    # 5 kg held about 0.35 m ahead: the static lean (11-25 deg), reached within its rate.
    assert math.radians(11.0) < settled <= LEAN_MAX
    assert leans_a[-1] == 0.0


def test_no_lean_when_switched_off() -> None:
    ctl = _controller(trunk_lean=False)
    assert ctl.lean is None
    out = ctl._lean_limited(1.0, 0.03, np.full(21, 0.3))
    np.testing.assert_array_equal(out, 0.0)
