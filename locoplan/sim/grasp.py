"""Grasping and conveyor belts: the physics the plain contact model does not give.

Grasp. A hand closes on an object when the plan says the hand reaches it (the pick's grasp instant)
AND the hand really touches it in MuJoCo: every planned hand must be within GRASP_TOLERANCE (the
robot's: its hand radius + 1 cm) of the object's surface. Closing switches on a point connection
(MuJoCo `connect` equality) between the hand point and the object at their current positions (so
nothing jumps or teleports); hands are point contacts, as in the paper (3-D forces, no moments). A
6-D weld per hand was tried first: with 3-DoF arms, two welds close a kinematic loop with no
mobility left, so the hands could not move the box and the arm torques blew up. from then on the
object's weight reaches the robot through the hands in the physics. At the planned release instant
(drop or throw) the welds are switched off. If the hands are not there by GRASP_WINDOW after the
planned lift-off, the grasp fails (an event, and the object stays where it is), which the metrics
turn into a failed pick.

Palms. The point connections leave a box free to turn about the line through the two hands (the
grip axis), and nothing in them damps it: carried boxes swung 20-60 deg in loaded turns and
walks, and their swing shook the robot. Real hands press the box between two palms, whose
contact patches transmit a torsional friction torque about that axis.
`GraspManager.palm_torques` models it: while two hands hold an object, a rotational spring-
damper about the grip axis keeps the object at the orientation it had relative to the trunk at
the grasp (wrists, which HECTOR's 3-DoF arms lack, would keep a held box's attitude; so a box
picked level stays level whatever the elbows do), critically damped at PALM_BOND_FREQUENCY for
the object's own inertia about the axis (more for an object gripped off its centre, so that its
weight's moment deflects it at most PALM_BOND_DEFLECTION: `palm_bond_frequency`), and capped at
the palms' friction limit (4/3) m g r_palm: each palm squeezes with N = m g / mu, twice what
holding the weight by friction needs, and a uniformly pressed disc of radius r_palm transmits
(2/3) mu N r_palm. The cap exceeds the largest gravity torque of a held box (gripped at most
GRASP_ABOVE_CENTRE = 0.04 m off its centre) for any mass, so a held box hangs level and swings
only as far as an inertial torque beyond the cap pushes it. The reaction goes to the two hand
bodies in equal halves, so momentum is conserved. The bond acts on every object held by two
hands: without it the 14 kg standing hold pitched its block 35-60 deg in the grasp and, once the
robot's retreat from the table began, fell forward; with it the block stays level.

Conveyor. A belt moving at `speed` along the conveyor's own x axis drags objects resting on it
by friction: a horizontal force c m (v_belt - v_object), clamped to mu m g, while the object
touches the conveyor's top (a simple model of a belt).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt
from numba import njit

from locoplan.plan.constants import GRASP_TOLERANCE
from locoplan.plan.manipulation import ObjectHold
from locoplan.sim.scene import Scene

FloatArray = npt.NDArray[np.float64]

GRASP_EARLY = 0.05  # s before the planned grasp instant the hands may close
GRASP_WINDOW = 0.25  # s after the planned lift-off the grasp may still close
BELT_GAIN = 20.0  # 1/s: how fast the belt's friction brings an object to belt speed
BELT_MU = 0.8  # belt friction coefficient for the drag clamp
PALM_RADIUS = 0.04  # m, radius of the palm contact patch (an 8 cm wide hand)
GRAVITY = 9.81
PALM_BOND_FREQUENCY = 20.0  # rad/s, natural frequency of the palm bond (critically damped)

_EQUALITY = int(mujoco.mjtConstraint.mjCNSTR_EQUALITY)


# An explicit signature (MuJoCo's efc arrays: int32 types and ids, float64 forces): compiled
# or loaded from the cache at import, never in the middle of a run.
@njit("int64(int32[:], int32[:], float64[:], int32, int64[:], float64[:])", cache=True)
def _weld_forces(
    efc_type: npt.NDArray[np.int32],
    efc_id: npt.NDArray[np.int32],
    efc_force: FloatArray,
    equality: int,
    welds: npt.NDArray[np.int64],
    out: FloatArray,
) -> int:
    """For each equality constraint in `welds`, the force of its third constraint row (a
    `connect`'s world z row) into `out`, NaN unless it has exactly three rows; returns how
    many equality rows there are. What `hand_load` read with four numpy calls per hand
    (10-15 us a tick inside the loop), in one pass over the rows."""
    n_eq = 0
    counts = np.zeros(welds.shape[0], dtype=np.int64)
    for r in range(efc_type.shape[0]):
        if efc_type[r] != equality:
            continue
        n_eq += 1
        for j in range(welds.shape[0]):
            if efc_id[r] == welds[j]:
                counts[j] += 1
                if counts[j] == 3:
                    out[j] = efc_force[r]
    for j in range(welds.shape[0]):
        if counts[j] != 3:
            out[j] = np.nan
    return n_eq


# Integer work only (the contact array's geom pairs): compiled or loaded from the cache at
# import, like `_weld_forces`.
@njit("int64(int32[:, :], boolean[:], int64, int64[:])", cache=True)
def _contacts_of(
    pairs: npt.NDArray[np.int32],
    other: npt.NDArray[np.bool_],
    geom: int,
    out: npt.NDArray[np.int64],
) -> int:
    """Indices (ascending, into `out`; how many returned) of the contacts whose geom pair
    `pairs` (ncon, 2) joins `geom` with a geom marked in `other` (ngeom,), either order. What
    `hand_load` and `ConveyorDrive.apply` found with five numpy calls or two Python sets of
    every pair (4-6 us a tick in the loop), in one pass."""
    n = 0
    for i in range(pairs.shape[0]):
        g1 = pairs[i, 0]
        g2 = pairs[i, 1]
        if (g1 == geom and other[g2]) or (g2 == geom and other[g1]):
            out[n] = i
            n += 1
    return n


# Largest deflection (rad) the weight's moment about the grip line may give a held object in
# the palm bond: the bond's frequency is raised, per object, until its stiffness I w^2 holds
# m g d (d the object's centre of mass's horizontal distance from the line through the two
# hands, measured when the grasp closes) within it (`palm_bond_frequency`). Why: I w^2 scales
# with the box's size squared while m g d does not; at 20 rad/s a 0.10 m box gripped 3 cm
# behind its centre (the planner's GRIP_BEHIND_CENTRE) deflects 25 deg. HECTOR seed 73021's
# transfer-004 (5.83 kg, 0.109 x 0.115 x 0.122 m, gripped 2.5 cm behind) hung 15-18 deg
# nose-down, its far bottom corner 4 cm under the plan's box, caught the 0.548 m platform's
# edge in the turn and the robot fell. 3 deg is what pressed palm pads give before they slip
# (the friction cap still bounds the torque). Raising the frequency for every object instead
# (60 rad/s) sank the 14 kg standing hold's block back onto its table (its arms take the
# bond's reaction). Explicit at the 1 ms physics step: w dt stays far below 1 (0.06 for the
# 0.10 m box).
PALM_BOND_DEFLECTION = math.radians(3.0)


def palm_bond_frequency(mass: float, inertia_axis: float, offset: float) -> float:
    """Natural frequency (rad/s) of the palm bond of an object of `mass` kg whose inertia
    about the grip line's direction through its centre is `inertia_axis` kg m^2 and whose
    centre of mass stands `offset` m (horizontally) off the grip line: PALM_BOND_FREQUENCY, or
    more where the weight's moment m g d would deflect the bond beyond PALM_BOND_DEFLECTION,
    w^2 = m g d / (I PALM_BOND_DEFLECTION)."""
    if inertia_axis <= 0.0:
        return PALM_BOND_FREQUENCY
    need = mass * GRAVITY * abs(offset) / (inertia_axis * PALM_BOND_DEFLECTION)
    return max(PALM_BOND_FREQUENCY, math.sqrt(need))


@dataclass(slots=True)
class _HoldState:
    hold: ObjectHold
    hands: tuple[int, ...]
    state: str = "waiting"  # waiting | grasped | released | failed
    grasp_time: float | None = None
    release_time: float | None = None


def surface_distance(scene: Scene, data: mujoco.MjData, name: str, point: FloatArray) -> float:
    """Distance (m) from a world point to the object's surface (0 inside the object)."""
    bid = scene.object_body_ids[name]
    R = data.xmat[bid].reshape(3, 3)
    local = R.T @ (point - data.xpos[bid])
    ob = scene.object_defs[name]
    if ob.shape == "sphere":
        return max(0.0, float(np.linalg.norm(local)) - ob.size[0])
    half = np.asarray(ob.size) / 2.0
    return float(np.linalg.norm(np.maximum(np.abs(local) - half, 0.0)))


class GraspManager:
    """Closes and opens the grasp welds following the plan and the measured hand positions."""

    def __init__(
        self, scene: Scene, holds: tuple[ObjectHold, ...], tolerance: float = GRASP_TOLERANCE
    ) -> None:
        """`tolerance` (m): how near every planned hand point must come to the object's
        surface for the hands to close (the plan's robot's `PlanGeometry.grasp_tolerance`;
        HECTOR's GRASP_TOLERANCE by default)."""
        self.scene = scene
        self.tolerance = tolerance
        side = {"L": 0, "R": 1}
        self.holds = [_HoldState(h, tuple(side[x] for x in h.hands)) for h in holds]
        self._hand_sites = [
            mujoco.mj_name2id(scene.model, mujoco.mjtObj.mjOBJ_SITE, s)
            for s in scene.robot.hand_frames
        ]

        self._palm_refs: dict[str, FloatArray] = {}
        # Each held object's palm-bond frequency (rad/s, `palm_bond_frequency`).
        self._palm_freq: dict[str, float] = {}
        m = scene.model
        self._hand_geoms = {
            g
            for g in range(m.ngeom)
            if int(m.geom_bodyid[g]) in scene.hand_body_ids and int(m.geom_contype[g]) != 0
        }
        # Per geom id, whether it is a colliding hand geom (a lookup for `hand_load`'s scan
        # of the contact array: np.isin cost 10 us per tick).
        self._is_hand_geom = np.zeros(m.ngeom, dtype=bool)
        self._is_hand_geom[sorted(self._hand_geoms)] = True
        self._trunk_body = mujoco.mj_name2id(
            scene.model, mujoco.mjtObj.mjOBJ_BODY, scene.robot.trunk_body
        )
        self._palm_bodies: set[int] = set()
        # `hand_load`'s equality constraints (the grasp welds) and their third rows' forces.
        self._weld_index = {key: j for j, key in enumerate(scene.grasp_welds)}
        self._weld_ids = np.array(list(scene.grasp_welds.values()), dtype=np.int64)
        self._weld_out = np.zeros(len(self._weld_ids))
        # `palm_torques`' per-body constants: the principal inertias and the bond torque's cap
        # (4/3 m g PALM_RADIUS, module docstring), and the MjData views it reads.
        self._body_inertia = np.array(m.body_inertia)
        self._palm_caps = [
            (4.0 / 3.0) * float(m.body_mass[b]) * GRAVITY * PALM_RADIUS for b in range(m.nbody)
        ]
        self._views_of: mujoco.MjData | None = None
        self._views: tuple[FloatArray, FloatArray, FloatArray, FloatArray] | None = None
        self._quat = np.zeros(4)  # `palm_torques`' scratch for MuJoCo's conversions
        self._err = np.zeros(3)

    def palm_torques(self, data: mujoco.MjData) -> None:
        """Set the palm-bond torques (module docstring) in `data.xfrc_applied` for every object
        held by two hands; clear them on the hand bodies once nothing is held.

        It runs every control tick: the MjData arrays it reads are taken once per `data`
        (`_palm_views`: fixed-size views, MuJoCo does not move them) and each object's weight
        cap once, the arithmetic as written in the module docstring (the same operations in
        the same order: the torques are the same to the bit)."""
        xmat, _, cvel, xfrc = self._palm_views(data)
        for bid in self._palm_bodies:
            xfrc[bid, 3:6] = 0.0
        self._palm_bodies.clear()
        for hs in self.holds:
            if hs.state != "grasped" or len(hs.hands) != 2:
                continue
            name = hs.hold.object
            refs = self._palm_refs.get(name)
            if refs is None:
                continue
            ob = self.scene.object_body_ids[name]
            tb = self._trunk_body
            R_obj = xmat[ob].reshape(3, 3)
            R_des = xmat[tb].reshape(3, 3) @ refs
            quat, err = self._quat, self._err
            mujoco.mju_mat2Quat(quat, (R_obj @ R_des.T).reshape(9))
            mujoco.mju_quat2Vel(err, quat, 1.0)
            rate = cvel[ob, 0:3] - cvel[tb, 0:3]
            inertia = self._world_inertia(data, ob)
            w = self._palm_freq.get(name, PALM_BOND_FREQUENCY)
            torque = -(inertia @ (w * w * err + 2.0 * w * rate))
            cap = self._palm_caps[ob]
            # (np.linalg.norm's own arithmetic for a vector, without its checks.)
            size = math.sqrt(torque.dot(torque))
            if size > cap:
                torque *= cap / size
            xfrc[ob, 3:6] = torque
            for k in hs.hands:
                hb = self.scene.hand_body_ids[k]
                xfrc[hb, 3:6] -= 0.5 * torque
                self._palm_bodies.add(hb)
            self._palm_bodies.add(ob)

    def _palm_views(
        self, data: mujoco.MjData
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """`data`'s xmat, ximat, cvel and xfrc_applied, taken once per MjData (each access
        builds a new view: about 0.5 us apiece, eight a tick)."""
        views = self._views
        if views is None or self._views_of is not data:
            views = (data.xmat, data.ximat, data.cvel, data.xfrc_applied)
            self._views, self._views_of = views, data
        return views

    def hand_load(self, data: mujoco.MjData) -> float:
        """Vertical force (N, positive up) that the closed grasps exert on the held objects:
        what wrist force sensors would read as the carried weight (plus its inertia). From
        the `connect` constraints' forces (three world-axis rows each)."""
        if not any(hs.state == "grasped" for hs in self.holds) or data.nefc == 0:
            return 0.0
        welds = self._weld_ids
        forces = self._weld_out
        if _weld_forces(data.efc_type, data.efc_id, data.efc_force, _EQUALITY, welds, forces) == 0:
            return 0.0
        total = 0.0
        for hs in self.holds:
            if hs.state != "grasped":
                continue
            for k in hs.hands:
                f = forces[self._weld_index[(hs.hold.object, k)]]
                if not math.isnan(f):
                    # Rows act along world x, y, z on body 1 (the hand) with +force and on
                    # body 2 (the object) with -force.
                    total -= float(f)
            # The hand spheres also press on the object and carry part of it by friction.
            obj_geom = self.scene.object_geom_ids[hs.hold.object]
            ncon = data.ncon
            if ncon == 0:
                continue
            touching = np.empty(ncon, dtype=np.int64)
            n_touch = _contacts_of(data.contact.geom, self._is_hand_geom, obj_geom, touching)
            wrench = np.zeros(6)
            for i in touching[:n_touch].tolist():
                c = data.contact[i]
                g2 = int(c.geom2)
                mujoco.mj_contactForce(self.scene.model, data, i, wrench)
                f_world = c.frame.reshape(3, 3).T @ wrench[:3]  # on geom2, from geom1
                total += float(f_world[2]) if g2 == obj_geom else -float(f_world[2])
        return total

    def _world_inertia(self, data: mujoco.MjData, body: int) -> FloatArray:
        """Inertia tensor (3, 3) kg m^2 of `body` about its centre, in world axes (its
        principal axes R_i: R_i diag(I) R_i^T)."""
        R_i = self._palm_views(data)[1][body].reshape(3, 3)
        # (R_i scaled column-wise: R_i diag(I) without forming the diagonal matrix.)
        return np.asarray((R_i * self._body_inertia[body]) @ R_i.T)

    def _bond_frequency(self, name: str, hands: tuple[int, ...], data: mujoco.MjData) -> float:
        """`palm_bond_frequency` of object `name` as the grasp closes: the grip line through
        the two hand points, the object's inertia about that direction through its centre
        (world inertia tensor from its principal axes) and its centre's horizontal distance
        from the line. PALM_BOND_FREQUENCY for a one-handed grasp."""
        if len(hands) != 2:
            return PALM_BOND_FREQUENCY
        a, b = (data.site_xpos[self._hand_sites[k]] for k in hands)
        line = b - a
        size = float(np.linalg.norm(line))
        if size < 1e-9:
            return PALM_BOND_FREQUENCY
        u = line / size
        ob = self.scene.object_body_ids[name]
        m = self.scene.model
        inertia = self._world_inertia(data, ob)
        # The weight's moment about the line is m g (z x u) . r, r from a hand point to the
        # centre: its lever, the centre's horizontal distance across the line.
        across = np.cross(np.array([0.0, 0.0, 1.0]), u)
        lever = float((data.xipos[ob] - a).dot(across))
        return palm_bond_frequency(float(m.body_mass[ob]), float(u @ inertia @ u), lever)

    def held_objects(self) -> set[str]:
        """Objects currently welded to a hand."""
        return {h.hold.object for h in self.holds if h.state == "grasped"}

    def update(self, t: float, data: mujoco.MjData) -> list[tuple[str, dict[str, object]]]:
        """Advance the grasp state machine at time t (s); returns (event kind, fields)."""
        events: list[tuple[str, dict[str, object]]] = []
        for hs in self.holds:
            h = hs.hold
            name = h.object
            if hs.state == "waiting" and t >= h.grasp - GRASP_EARLY:
                gaps = [
                    surface_distance(self.scene, data, name, data.site_xpos[self._hand_sites[k]])
                    for k in hs.hands
                ]
                if max(gaps) <= self.tolerance:
                    for k in hs.hands:
                        self._close(name, k, data)
                    R_obj = data.xmat[self.scene.object_body_ids[name]].reshape(3, 3)
                    R_trunk = data.xmat[self._trunk_body].reshape(3, 3)
                    self._palm_refs[name] = R_trunk.T @ R_obj
                    self._palm_freq[name] = self._bond_frequency(name, hs.hands, data)
                    hs.state = "grasped"
                    hs.grasp_time = t
                    events.append(("grasp", {"object": name, "gap_m": round(max(gaps), 4)}))
                elif t > h.lift + GRASP_WINDOW:
                    hs.state = "failed"
                    events.append(
                        (
                            "grasp_failed",
                            {"object": name, "gap_m": round(max(gaps), 4), "hands": list(h.hands)},
                        )
                    )
            if hs.state == "grasped" and t >= h.release:
                for k in hs.hands:
                    data.eq_active[self.scene.grasp_welds[(name, k)]] = 0
                hs.state = "released"
                hs.release_time = t
                events.append(("release", {"object": name, "how": h.release_kind or ""}))
        return events

    def _close(self, name: str, hand: int, data: mujoco.MjData) -> None:
        m = self.scene.model
        eq = self.scene.grasp_welds[(name, hand)]
        b1 = self.scene.hand_body_ids[hand]
        b2 = self.scene.object_body_ids[name]
        # Connect data: the anchor in body1's frame (3) and in body2's frame (3). Both are the
        # hand point now, so the constraint starts satisfied.
        p = data.site_xpos[self._hand_sites[hand]]
        m.eq_data[eq, 0:3] = data.xmat[b1].reshape(3, 3).T @ (p - data.xpos[b1])
        m.eq_data[eq, 3:6] = data.xmat[b2].reshape(3, 3).T @ (p - data.xpos[b2])
        data.eq_active[eq] = 1


class ConveyorDrive:
    """Belt friction on objects resting on moving conveyors (applied every physics step)."""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.belts = [
            (scene.fixture_geom_ids[name], fx.speed, fx.yaw)
            for name, fx in scene.fixture_defs.items()
            if fx.kind == "conveyor" and fx.speed != 0.0
        ]
        m = scene.model
        self._objects = [
            (
                name,
                scene.object_body_ids[name],
                scene.object_geom_ids[name],
                int(m.jnt_dofadr[m.body_jntadr[scene.object_body_ids[name]]]),
                scene.object_defs[name].mass,
            )
            for name in scene.object_body_ids
        ]
        # Per belt, its geom marked in an array over the model's geoms (`_contacts_of`).
        self._belt_marks: list[npt.NDArray[np.bool_]] = []
        for belt_geom, _, _ in self.belts:
            mark = np.zeros(m.ngeom, dtype=bool)
            mark[belt_geom] = True
            self._belt_marks.append(mark)

    def apply(self, data: mujoco.MjData, held: set[str]) -> None:
        if not self.belts:
            return
        ncon = data.ncon
        pairs = data.contact.geom if ncon else None
        found = np.empty(ncon, dtype=np.int64)
        for name, bid, gid, dof, mass in self._objects:
            force = np.zeros(3)
            if name not in held and pairs is not None:
                for (_, speed, yaw), mark in zip(self.belts, self._belt_marks, strict=True):
                    if _contacts_of(pairs, mark, gid, found):
                        v_belt = speed * np.array([math.cos(yaw), math.sin(yaw)])
                        dv = v_belt - data.qvel[dof : dof + 2]
                        f = BELT_GAIN * mass * dv
                        limit = BELT_MU * mass * 9.81
                        norm = math.sqrt(f.dot(f))  # np.linalg.norm's arithmetic
                        if norm > limit:
                            f *= limit / norm
                        force[:2] += f
            data.xfrc_applied[bid, :3] = force
