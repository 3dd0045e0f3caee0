"""Rigid-body dynamics of the robot with pinocchio, in pinocchio's free-flyer convention.

q (nq = 7 + nj): p_base_world, quaternion (x, y, z, w), joint angles in
`RobotDescription.joint_names` order. v (nv = 6 + nj): base linear and angular velocity in
the base frame, then joint rates. See `locoplan.robot.conventions` for the MuJoCo mapping.

`PinocchioRobot.update(q, v)` runs every algorithm a whole-body controller needs in one pass
(about 10 us on the reference machine); the accessors then read the cached results. Frame
quantities use pinocchio's LOCAL_WORLD_ALIGNED convention: linear parts are the velocity /
acceleration of the frame origin in world axes, angular parts the frame's angular velocity /
acceleration in world axes; 6-vectors and 6-row Jacobians are ordered (linear, angular).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from locoplan.exceptions import RobotDescriptionError
from locoplan.robot.description import RobotDescription

FloatArray = NDArray[np.float64]
_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


class Pose(NamedTuple):
    """A frame's placement: origin in world coordinates (3,) and R_frame_to_world (3, 3)."""

    p_world: FloatArray
    R_to_world: FloatArray


class PinocchioRobot:
    """Pinocchio model and data of one robot, built from the description's MJCF file.

    Call `update(q, v)` once per control tick before using the accessors; they return
    copies of results computed at the last update. `gravity(q)` is independent of it.
    """

    def __init__(self, desc: RobotDescription) -> None:
        model = pin.buildModelFromMJCF(str(desc.mjcf_path))
        nj = desc.n_joints
        if model.nq != 7 + nj or model.nv != 6 + nj:
            raise RobotDescriptionError(
                f"{desc.mjcf_path}: pinocchio built nq={model.nq}, nv={model.nv}; "
                f"expected a free flyer and {nj} hinges (nq={7 + nj}, nv={6 + nj})"
            )
        if tuple(model.names)[2:] != desc.joint_names:
            raise RobotDescriptionError(
                f"{desc.mjcf_path}: pinocchio joint order {list(model.names)[2:]} "
                f"differs from robot.yaml {list(desc.joint_names)}"
            )
        # The MJCF parser leaves these at +inf (MJCF has no velocity limits, and the parser
        # does not read actuator ctrlrange); keep the pinocchio model self-consistent.
        model.effortLimit[6:] = desc.torque_limits
        model.velocityLimit[6:] = desc.velocity_limits
        self.desc = desc
        self.model = model
        self.data = model.createData()
        self._gravity_data = model.createData()
        # Body and site frames first: a joint frame never shadows a body or site name.
        self._frame_ids: dict[str, int] = {}
        for kind in (pin.FrameType.BODY, pin.FrameType.OP_FRAME, pin.FrameType.JOINT):
            for fid, frame in enumerate(model.frames):
                if frame.type == kind:
                    self._frame_ids.setdefault(frame.name, fid)
        for name in (desc.trunk_body, desc.imu_site, *desc.foot_frames, *desc.hand_frames):
            self.frame_id(name)
        self._zero_a = np.zeros(model.nv)
        self._q = pin.neutral(model)
        self._v = np.zeros(model.nv)
        self._total_mass = float(pin.computeTotalMass(model))
        self.update(self.nominal_q(), self._v)

    # ------------------------------------------------------------------ set-up helpers
    @property
    def nq(self) -> int:
        return int(self.model.nq)

    @property
    def nv(self) -> int:
        return int(self.model.nv)

    def frame_id(self, name: str) -> int:
        """Cached pinocchio frame index of a body, site or joint name."""
        try:
            return self._frame_ids[name]
        except KeyError:
            raise KeyError(f"robot {self.desc.name!r} has no frame {name!r}") from None

    def nominal_q(self) -> FloatArray:
        """Nominal configuration (nq,): trunk upright at the nominal height above x=y=0."""
        q = pin.neutral(self.model)
        q[2] = self.desc.base_height_nominal
        q[7:] = self.desc.q_joints_nominal
        return np.asarray(q, dtype=np.float64)

    # ------------------------------------------------------------------ per-tick update
    def update(self, q: FloatArray, v: FloatArray) -> None:
        """Compute M, h, kinematics, Jacobians, drifts and CoM at (q (nq,), v (nv,)).

        Jacobian drifts come from forward kinematics with zero joint acceleration: the
        classical acceleration of a frame at a = 0 is exactly Jdot v.
        """
        model, data = self.model, self.data
        self._q = np.array(q, dtype=np.float64)
        self._v = np.array(v, dtype=np.float64)
        # WORLD convention: fills the whole symmetric M and data.oYcrb (composite inertias).
        pin.crba(model, data, self._q, pin.Convention.WORLD)
        pin.nonLinearEffects(model, data, self._q, self._v)
        pin.forwardKinematics(model, data, self._q, self._v, self._zero_a)
        pin.computeJointJacobians(model, data)
        pin.updateFramePlacements(model, data)
        pin.centerOfMass(model, data, pin.KinematicLevel.VELOCITY, False)

    @property
    def q(self) -> FloatArray:
        """Configuration (nq,) of the last update."""
        return self._q.copy()

    @property
    def v(self) -> FloatArray:
        """Velocity (nv,) of the last update."""
        return self._v.copy()

    @property
    def M(self) -> FloatArray:
        """Joint-space inertia matrix (nv, nv), symmetric, rotor armature included (kg m^2)."""
        return np.array(self.data.M)

    @property
    def h(self) -> FloatArray:
        """Nonlinear effects C(q, v) v + g(q) (nv,), generalized forces in pinocchio basis."""
        return np.array(self.data.nle)

    def gravity(self, q: FloatArray) -> FloatArray:
        """Generalized gravity g(q) (nv,) at any q; does not disturb the last update."""
        return np.array(pin.computeGeneralizedGravity(self.model, self._gravity_data, q))

    @property
    def total_mass(self) -> float:
        """Total mass (kg)."""
        return self._total_mass

    @property
    def com_position(self) -> FloatArray:
        """Centre of mass in world coordinates (3,), m."""
        return np.array(self.data.com[0])

    @property
    def com_velocity(self) -> FloatArray:
        """Centre-of-mass velocity in world coordinates (3,), m/s."""
        return np.array(self.data.vcom[0])

    def composite_inertia_world(self) -> FloatArray:
        """Rotational inertia (3, 3) of the whole robot about its CoM, world axes (kg m^2).

        The locked-joint (composite rigid body) inertia of the current posture, the same as
        pinocchio's centroidal `data.Ig` angular block.
        """
        return np.array(self.data.oYcrb[0].inertia)

    def inertia_without_joints_world(self, joints: tuple[str, ...]) -> FloatArray:
        """Rotational inertia (3, 3) (kg m^2, world axes) of the bodies moved by every joint
        but `joints` (names; the free flyer's body included), about their own CoM, at the
        last update: the locked-joint inertia of the robot less those joints' bodies."""
        model, data = self.model, self.data
        left_out = {model.getJointId(name) for name in joints}
        if model.njoints in left_out:
            raise RobotDescriptionError(f"unknown joint among {list(joints)}")
        total = pin.Inertia.Zero()
        for j in range(1, model.njoints):
            if j not in left_out:
                total += data.oMi[j].act(model.inertias[j])
        return np.array(total.inertia)

    def joint_axis_world(self, name: str) -> tuple[FloatArray, FloatArray]:
        """A hinge's origin (3,) (m) and unit axis (3,), world coordinates, at the last
        update (the axis: the angular part of the joint's own Jacobian column)."""
        model = self.model
        jid = model.getJointId(name)
        if jid >= model.njoints or model.joints[jid].nv != 1:
            raise RobotDescriptionError(f"{name!r} is not a hinge of the model")
        J = pin.getJointJacobian(model, self.data, jid, _LWA)
        axis = np.array(J[3:, model.joints[jid].idx_v])
        return np.array(self.data.oMi[jid].translation), axis

    def hip_pitch_joints(self) -> tuple[int, ...]:
        """Each leg's hip pitch (index into the joints) at the nominal pose: its first joint
        from the trunk whose axis is the trunk's lateral one (within 25 deg); a leg without
        one contributes its first joint. (Own pinocchio data: the last update is kept.)"""
        model, desc = self.model, self.desc
        data = model.createData()
        pin.computeJointJacobians(model, data, self.nominal_q())
        out = []
        for leg in desc.leg_joint_indices:
            joints = [int(j) for j in leg]
            pitch = joints[0]
            for j in joints:
                jid = model.getJointId(desc.joint_names[j])
                axis = pin.getJointJacobian(model, data, jid, _LWA)[3:, 6 + j]
                if abs(axis[1]) > math.cos(math.radians(25.0)) * np.linalg.norm(axis):
                    pitch = j
                    break
            out.append(pitch)
        return tuple(out)

    # ------------------------------------------------------------------ frames
    def frame_pose(self, name: str) -> Pose:
        """Placement of a frame at the last update."""
        placement = self.data.oMf[self.frame_id(name)]
        return Pose(np.array(placement.translation), np.array(placement.rotation))

    def frame_position(self, name: str) -> FloatArray:
        """Frame origin in world coordinates (3,), m."""
        return np.array(self.data.oMf[self.frame_id(name)].translation)

    def frame_rotation(self, name: str) -> FloatArray:
        """R_frame_to_world (3, 3)."""
        return np.array(self.data.oMf[self.frame_id(name)].rotation)

    def frame_jacobian(self, name: str) -> FloatArray:
        """Frame Jacobian (6, nv), LOCAL_WORLD_ALIGNED: [v_origin_world; omega_world] = J v."""
        return np.array(pin.getFrameJacobian(self.model, self.data, self.frame_id(name), _LWA))

    def frame_velocity(self, name: str) -> FloatArray:
        """[v_origin_world; omega_world] (6,) = J v, m/s and rad/s."""
        velocity = pin.getFrameVelocity(self.model, self.data, self.frame_id(name), _LWA)
        return np.array(velocity.vector)

    def frame_jdot_v(self, name: str) -> FloatArray:
        """Drift Jdot v (6,) of `frame_jacobian`: the frame's [p_ddot; omega_dot] at a = 0.

        The linear part is the classical (not spatial) acceleration of the frame origin, so
        that p_ddot_world = J a + Jdot v holds for the LOCAL_WORLD_ALIGNED J above.
        """
        acc = pin.getFrameClassicalAcceleration(self.model, self.data, self.frame_id(name), _LWA)
        return np.array(acc.vector)

    def frames_kinematics(
        self, names: tuple[str, ...]
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Positions (n, 3), rotations (n, 3, 3), Jacobians (n, 6, nv) and drifts (n, 6) of
        several frames at the last update, stacked for the control loop (the same values as
        `frame_position`, `frame_rotation`, `frame_jacobian` and `frame_jdot_v`)."""
        model, data = self.model, self.data
        n = len(names)
        p = np.empty((n, 3))
        R = np.empty((n, 3, 3))
        J = np.empty((n, 6, model.nv))
        dJv = np.empty((n, 6))
        for i, name in enumerate(names):
            fid = self.frame_id(name)
            placement = data.oMf[fid]
            p[i] = placement.translation
            R[i] = placement.rotation
            J[i] = pin.getFrameJacobian(model, data, fid, _LWA)
            dJv[i] = pin.getFrameClassicalAcceleration(model, data, fid, _LWA).vector
        return p, R, J, dJv

    def base_pose(self) -> Pose:
        """Trunk (free-flyer) placement: p_base_world and R_base_to_world."""
        return self.frame_pose(self.desc.trunk_body)

    def base_velocity_world(self) -> FloatArray:
        """[v_base_origin_world; omega_base_world] (6,) at the last update."""
        return self.frame_velocity(self.desc.trunk_body)
