"""Trunk lean for a held load: pitch the trunk back so that the load adds no hip-pitch moment.

Why: in single support one hip pitch carries the whole upper body and whatever the hands
hold. The CoM shift (`LocoManipulationController._com_shift`) keeps the combined centre of
mass over the feet, but it moves the whole robot and leaves the upper body's moment about
the hips as it was: HECTOR carrying 7.8 kg at 0.2 m ahead of its trunk saturated the stance
hip pitch (33.5 N m) while stepping through a loaded turn, the trunk pitched forward, and it
fell (envelope seed 44021, walk-carry-000: static single-support hip-pitch ratio 0.57-0.83
at the logged postures, peaks 1.0). Pitching the trunk back by b about its origin moves the
hips forward under the trunk by -h_z sin b (below) while the upper body's centre of mass
(HECTOR: 14 of 17 kg, 0.20 m above the hips, at the trunk origin's height) stays where it
was: the same postures' single-support ratio falls by 0.12 per 5 deg of lean (pinocchio, the
logged configurations pitched back). The lab's loco-manipulation MPC leans its trunk back
about 3 deg per kg held in front (shared/robot.md); this lean comes out at a comparable
2.5-4.5 deg per kg for HECTOR's envelope loads, from the robot's masses rather than a rate.

The model (everything from the robot's description, at its nominal pose; trunk frame x
ahead, z up, lengths from the trunk origin): the upper body is every body not moved by a leg
joint, of mass m_u and centre of mass u = (u_x, u_z); the hips are the mean of the two hip
pitch joints' origins h = (h_x, h_z). A load of m kg is held `ahead` m in front of the trunk
origin (horizontal, world-fixed: the hands' carry targets are points of the trunk's yaw
frame, which the lean does not turn). With the trunk pitched back by b, the moment about the
hips of the upper body and the load, per g, is

    M(b, m) = m_u (x(u, b) - x(h, b)) + m (ahead - x(h, b)),  x(r, b) = r_x cos b - r_z sin b,

and the lean is the b in [0, LEAN_MAX] with M(b, m) = M(0, 0): the loaded upper body
balances on the hips as the unloaded one does (0 when the load is behind that point, LEAN_MAX
when even that lean leaves some of the load's moment). M falls monotonically with b over
[0, LEAN_MAX] when the upper body's centre of mass is above the hips, so a bisection finds it.

LEAN_MAX = 25 deg: the lean of HECTOR's heavier walk-carry loads (6-8 kg at the carry-in
distance, 0.20-0.26 m, ask 21-25 deg). The hips' forward travel (-h_z sin b) stretches the
stance leg: HECTOR's hip-to-ankle distance is 0.363 m upright, 0.388 m at 25 deg and 0.411 m
at 35 deg, of the 0.436 m its knee's 15 deg stop allows (H1: 0.739, 0.766, 0.786 of 0.793 m),
and a stepping leg needs some of what is left. The controller changes the lean no faster
than LEAN_RATE (`LocoManipulationController._lean_limited`).

Measured (README, Envelope), always paired with the code without it: on envelope seed
44021's 33 heaviest or failing manipulation runs (both strategies) 26 succeed with it (led by
the load like the CoM shift) against 21; on fresh seed 46021 386 of 400 against 387. Started
only once the load is wholly on (the controller's `_lean`), 11 of the 13 46021 runs the early
lean changed succeed against 7; then on fresh seed 47021 397 of 400 against 399, and H1 on
fresh seed 46027 199 of 200 (its one fall comes before the grasp, as without it). About
neutral on the envelope, so `ControllerSettings.trunk_lean` is off by default.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from locoplan.robot.pinocchio_model import PinocchioRobot

FloatArray = NDArray[np.float64]

LEAN_MAX = math.radians(25.0)
# Bisection steps: LEAN_MAX / 2^30 is far below what the trunk tracks.
_BISECTIONS = 30


class TrunkLean:
    """The lean of a robot's trunk for held loads (module docstring)."""

    def __init__(self, robot: PinocchioRobot, lean_max: float = LEAN_MAX) -> None:
        if not 0.0 <= lean_max < math.pi / 2:
            raise ValueError(f"lean_max must be in [0, pi/2), got {lean_max}")
        desc = robot.desc
        model = robot.model
        data = model.createData()
        q = robot.nominal_q()
        pin.forwardKinematics(model, data, q)
        base = np.asarray(q[:3], dtype=float)
        R = np.array(data.oMi[1].rotation)
        names = desc.joint_names
        legs = {model.getJointId(names[int(j)]) for leg in desc.leg_joint_indices for j in leg}
        mass = 0.0
        moment = np.zeros(3)
        for j in range(1, model.njoints):
            if j in legs:
                continue
            inertia = data.oMi[j].act(model.inertias[j])
            mass += inertia.mass
            moment += inertia.mass * np.asarray(inertia.lever)
        upper = R.T.dot(moment / mass - base)
        hips = [
            R.T.dot(np.asarray(data.oMi[model.getJointId(names[j])].translation) - base)
            for j in robot.hip_pitch_joints()
        ]
        hip = np.mean(hips, axis=0)
        self.upper_mass = float(mass)
        self.upper_com = (float(upper[0]), float(upper[2]))
        self.hip = (float(hip[0]), float(hip[2]))
        self.lean_max = float(lean_max)
        self._m0 = self._moment(np.zeros(1), np.zeros(1), np.zeros(1))[0]

    def _moment(self, lean: FloatArray, mass: FloatArray, ahead: FloatArray) -> FloatArray:
        """M(b, m) per g (kg m) of the module docstring, elementwise."""
        c, s = np.cos(lean), np.sin(lean)
        (ux, uz), (hx, hz) = self.upper_com, self.hip
        x_hip = hx * c - hz * s
        return self.upper_mass * (ux * c - uz * s - x_hip) + mass * (ahead - x_hip)

    def angles(self, mass: FloatArray, ahead: FloatArray) -> FloatArray:
        """The lean (rad, >= 0: trunk pitched back) for loads of `mass` kg held `ahead` m in
        front of the trunk origin, elementwise (module docstring)."""
        mass, ahead = np.broadcast_arrays(
            np.asarray(mass, dtype=float), np.asarray(ahead, dtype=float)
        )
        lo = np.zeros(mass.shape)
        hi = np.full(mass.shape, self.lean_max)
        m0 = self._m0
        needs = (mass > 0.0) & (self._moment(lo, mass, ahead) > m0)
        full = needs & (self._moment(hi, mass, ahead) >= m0)
        out = np.where(full, self.lean_max, 0.0)
        part = needs & ~full
        if part.any():
            a, b, m, x = lo[part], hi[part], mass[part], ahead[part]
            for _ in range(_BISECTIONS):
                mid = 0.5 * (a + b)
                above = self._moment(mid, m, x) > m0
                a = np.where(above, mid, a)
                b = np.where(above, b, mid)
            out[part] = 0.5 * (a + b)
        return out
