"""The MPC's rigid body and its stance-ankle torque bound, derived from the robot's model
(no simulation): closed forms on the nominal pose of HECTOR and H1."""

from __future__ import annotations

import numpy as np
import pytest

from locoplan.control.contact import (
    ContactLimits,
    ankle_row_binds,
    ankle_torque_row,
    torsion_bound,
)
from locoplan.control.controller import (
    ANKLE_TORQUE_SHARE,
    ControllerSettings,
    ankle_mpc_settings,
    ankle_rows,
    mpc_body_inertia,
)
from locoplan.control.mpc import MpcSettings, force_weights
from locoplan.control.mpc_terms import wrench_rows
from locoplan.robot.description import load_robot_description
from locoplan.robot.pinocchio_model import PinocchioRobot


def test_ankle_row_is_the_moment_about_the_axis() -> None:
    # Flat foot, axis y, sole d below the axis: M_ankle = My' - d Fx' (a x r = (-d, 0, 0)).
    d = 0.07
    row = ankle_torque_row(np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, -d]))
    assert np.allclose(row, [-d, 0.0, 0.0, 1.0, 0.0], atol=1e-15)
    # Against the cross product on a random wrench (world = foot yaw frame here).
    rng = np.random.default_rng(3)
    a = rng.normal(size=3)
    a /= np.linalg.norm(a)
    r = rng.normal(size=3)
    F, My, Mz = rng.normal(size=3), 1.3, -0.4
    M = np.array([0.0, My, Mz])
    w5 = np.array([F[0], F[1], F[2], My, Mz])
    assert abs(ankle_torque_row(a, r).dot(w5) - a.dot(M + np.cross(r, F))) < 1e-12


@pytest.mark.parametrize(("robot", "depth", "torque"), [("hector", 0.04, 33.5), ("h1", 0.07, 40.0)])
def test_ankle_rows_from_the_model(robot: str, depth: float, torque: float) -> None:
    # The sole sites lie `depth` straight below the ankle axes (hector.xml, h1.xml; 1e-12 m:
    # round-off of the forward kinematics).
    desc = load_robot_description(robot)
    row, limit = ankle_rows(PinocchioRobot(desc), desc)
    assert np.allclose(row, [-depth, 0.0, 0.0, 1.0, 0.0], atol=1e-12)
    assert limit == torque


def test_ankle_bound_only_where_the_foot_can_exceed_the_ankle() -> None:
    # HECTOR: 250 N (0.5 x 0.04 + 0.09) = 27.5 N m <= 33.5 N m, no row, MpcSettings unchanged
    # (the identity its metrics depend on). H1: 756.4 N (0.5 x 0.07 + 0.14) = 132 N m > 40.
    row_h = np.array([-0.04, 0.0, 0.0, 1.0, 0.0])
    hector = ContactLimits()
    assert not ankle_row_binds(row_h, hector, 33.5)
    mpc = ControllerSettings().mpc
    assert ankle_mpc_settings(mpc, hector, row_h, 33.5) is mpc
    assert ankle_row_binds(row_h, hector, 27.4)
    row = np.array([-0.07, 0.0, 0.0, 1.0, 0.0])
    h1 = ContactLimits(f_max=756.4, toe=0.14, heel=0.035)
    bounded = ankle_mpc_settings(mpc, h1, row, 40.0)
    assert bounded.ankle_row == tuple(row)
    assert bounded.ankle_torque == ANKLE_TORQUE_SHARE * 40.0


def test_mpc_wrench_rows_carry_the_ankle_row() -> None:
    base = MpcSettings(mu_torsion=0.02)
    C0, lo0, hi0 = wrench_rows(base)
    C, lo, hi = wrench_rows(
        MpcSettings(mu_torsion=0.02, ankle_row=(-0.07, 0, 0, 1, 0), ankle_torque=32.0)
    )
    assert np.array_equal(C[:-1], C0) and np.array_equal(lo[:-1], lo0)
    assert np.array_equal(hi[:-1], hi0)
    assert np.array_equal(C[-1], [-0.07, 0, 0, 1, 0]) and (lo[-1], hi[-1]) == (-32.0, 32.0)


def test_mpc_body_inertia() -> None:
    # Composite: pinocchio's locked-joint inertia (the controller's value before the choice).
    # Upper body: every body outside the legs about its own CoM; H1's legs are 42 % of its
    # mass and their lever below the CoM makes most of the composite pitch inertia.
    for robot, composite_yy, upper_yy in (("hector", 0.534, 0.176), ("h1", 5.268, 0.961)):
        desc = load_robot_description(robot)
        r = PinocchioRobot(desc)
        I_c = mpc_body_inertia(r, desc, "composite")
        I_u = mpc_body_inertia(r, desc, "upper-body")
        assert np.allclose(I_c, I_c.T) and np.allclose(I_u, I_u.T)
        assert abs(I_c[1, 1] - composite_yy) < 1e-3
        assert abs(I_u[1, 1] - upper_yy) < 1e-3
        assert np.all(np.linalg.eigvalsh(I_u) > 0)
    with pytest.raises(ValueError, match="unknown MPC body"):
        mpc_body_inertia(r, desc, "legs")


def test_force_weights_scale_with_the_mass() -> None:
    # HECTOR (17 kg up to 4e-15) gets the default weights themselves; H1 (51.437 kg) those
    # times (17 / 51.437)^2.
    hector = load_robot_description("hector")
    assert force_weights(hector.total_mass) is MpcSettings().r_diag
    h1 = load_robot_description("h1")
    k = (17.0 / 51.437) ** 2
    assert np.allclose(force_weights(h1.total_mass), np.asarray(MpcSettings().r_diag) * k)


def test_ankle_row_needs_a_positive_bound() -> None:
    with pytest.raises(ValueError, match="ankle_torque > 0"):
        MpcSettings(ankle_row=(-0.07, 0.0, 0.0, 1.0, 0.0), ankle_torque=0.0)


def test_torsion_bound_scales_with_the_foot_length() -> None:
    # HECTOR's 0.09 + 0.06 m foot gets 0.02 m exactly (ContactLimits' default); H1's
    # 0.14 + 0.035 m foot 0.02 x 0.175 / 0.15.
    assert torsion_bound(0.09, 0.06) == ContactLimits().mu_torsion == 0.02
    assert abs(torsion_bound(0.14, 0.035) - 0.02 * 0.175 / 0.15) < 1e-10
