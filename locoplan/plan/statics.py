"""Static balance and joint torques of a standing pose that holds a load at the hands.

The question (issue 12, item 1; the analysis of shared/robot.md): can the robot hold `mass` kg
with its hands at given points of the trunk frame, standing still, within its torque limits
and with its centre of mass over its feet? Everything robot-specific comes from the
`RobotDescription` (the MJCF's kinematics and masses through pinocchio, torque and joint
limits, sole and hand frames, the foot's toe and heel, the nominal pose), so a second robot
uses the same code.

Model and assumptions:
- Trunk upright, its origin `trunk_height` above the soles. Both feet flat at their nominal
  stance: where the nominal pose (`q_joints_nominal`, trunk above x = y = 0) puts the soles,
  on z = 0. The trunk may shift straight back by `shift` (m) relative to the feet, carrying
  the arms and the hand points with it (hand targets are trunk-frame points); it does not
  pitch (tilting the trunk about its own CoM barely moves the total CoM, robot.md).
- Inverse kinematics with pinocchio, damped least squares with joint limits clamped: each
  sole's position and orientation from the leg joints, each holding hand's point from its arm
  joints; joints in no limb and the arms of free hands stay at their nominal angles. An
  unreachable hand point is reported with the distance left (`reach_residual`); the torques
  are then those of the closest posture.
- Loads: the object's weight m g, split equally between the holding hands, acting straight
  down at the hand points (the object's own position is not modelled beyond that).
- Feet: line feet, each a toe point `foot_toe` ahead of and a heel point `foot_heel` behind
  its sole frame, each taking a 3-D force with fz >= 0 inside the friction pyramid (MU): the
  centre of pressure of each foot lies between -heel and +toe, no roll moment, a yaw moment
  only through friction.
- Static equilibrium in pinocchio's free-flyer basis: g(q) = S' tau + sum_c J_c' f_c, so
  tau = (g(q) - sum_c J_c' f_c)[6:] with the base rows of that sum zero (the hand loads
  among the f_c). The contact forces are chosen by a linear programme (scipy's HiGHS) that
  minimises the worst torque ratio max_i |tau_i| / limit_i; the payload limit is the largest
  mass for which some forces keep every ratio <= 1, also one linear programme per shift (no
  bisection needed: the feasible set is convex in (mass, forces), so the masses that work
  form an interval). Postures: `locoplan.plan.statics_posture`; the programmes:
  `locoplan.plan.statics_lp`.
- The shift: the combined centre of mass (robot plus the weight at the hands) must project
  inside the support, between the rearmost heel and the foremost toe along x. The shift is
  searched over [0, the most the legs allow]. The ratio is often flat over the shifts that
  balance (hip pitch carries the upper body's moment wherever the hips are), so the shift
  that puts the combined CoM at the middle of the support is kept unless a bounded search
  over the balanced range finds a ratio lower by more than RATIO_TIE; `com_margin` is the
  distance of the combined CoM from the nearer support edge along x at the shift used
  (negative: outside, when no shift can bring it inside).
- Not modelled: dynamics (the closed loop needs margin above these figures), contact-force
  bounds other than fz >= 0, the trunk's own lean, the object's inertia, joint-limit margins.

Timing (2 cores shared with running simulations, 22 poses of the repository's scripts):
building a robot's model 25-40 ms once per process (`static_model` caches it) and the legs'
reach 50 ms once per trunk height; `ratio_at_centre`, the compile-time check, 3.6 ms per pose
(median; at most 6.4); the full `analyse` with the payload limit 69 ms (at most 95), about 35
linear programmes of 2 ms each.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize_scalar

from locoplan.plan.statics_lp import ContactForces, max_payload, min_worst_ratio
from locoplan.plan.statics_posture import GRAVITY, HeldPose, StancePostures, StaticTerms
from locoplan.robot.description import RobotDescription, load_robot_description

__all__ = ["GRAVITY", "MU", "HeldPose", "StaticAnalysis", "StaticModel", "static_model"]

FloatArray = NDArray[np.float64]

# Friction coefficient of the feet's pyramids: the controller's (shared/robot.md).
MU = 0.5
# Search tolerance on the shift (m), and on ratios counted as the same optimum.
SHIFT_TOL = 1e-3
RATIO_TIE = 1e-3
# Points of the coarse scan of the payload limit over the shift range.
LIMIT_SCAN = 7


@dataclass(frozen=True, slots=True, eq=False)
class StaticAnalysis:
    """The static analysis of one `HeldPose` with `mass` kg (module docstring).

    `torque_ratio`: worst |tau_i| / limit_i (inf when no shift balances the robot) at joint
    `joint`; `com_margin` (m): the combined CoM inside the support along x (negative:
    outside); `com_x` (m): that CoM along x, and `support_x` (m): the support's rear and front
    edges, both in the stance's frame (x = 0 under the unshifted trunk origin); `reach_margin`
    (m): the smallest over the holding hands of the arm's longest reach minus the
    shoulder-to-target distance, or minus the residual (`reach_residual`, m) of a target out
    of reach; `shift` (m): the trunk's shift back used, at most `shift_max` (the most the legs
    allow); `shift_range` (m): the shifts whose combined CoM is inside the support along x
    (None: none); `payload_limit` (kg): the mass at which the worst ratio reaches 1.0 (0 when
    even no load is held within the limits); `tau` (n_joints,) N m; `f_contacts`
    (2 x n_feet, 3) N, world: each foot's toe then heel force; `q` (nq,) the posture in
    pinocchio's convention.
    """

    mass: float
    balanced: bool
    torque_ratio: float
    joint: str
    com_margin: float
    com_x: float
    support_x: tuple[float, float]
    reach_margin: float
    reach_residual: tuple[float, ...]
    shift: float
    shift_max: float
    shift_range: tuple[float, float] | None
    payload_limit: float
    tau: FloatArray
    f_contacts: FloatArray
    q: FloatArray


class StaticModel:
    """One robot's static analysis (module docstring); build it once (`static_model`)."""

    def __init__(self, desc: RobotDescription, mu: float = MU) -> None:
        if not mu > 0.0:
            raise ValueError(f"mu must be positive, got {mu}")
        self.postures = StancePostures(desc)
        self.desc = desc
        self.mu = mu
        self.model = self.postures.model
        self.mass = self.postures.mass
        self.q_nominal = self.postures.q_nominal
        self.support_x = self.postures.support_x
        self.max_reach = self.postures.max_reach
        self._centre_ratios: dict[tuple[HeldPose, float], float] = {}

    def leg_reach(self, height: float) -> float:
        """The most the trunk can shift back (m) at `height` with the soles flat."""
        return self.postures.leg_reach(height)

    def _com_x(self, terms: StaticTerms, mass: float) -> float:
        """Combined CoM of robot and load along x (m)."""
        return float((self.mass * terms.com[0] + mass * terms.p_load[0]) / (self.mass + mass))

    def _solve(self, terms: StaticTerms, mass: float) -> ContactForces | None:
        lim = self.desc.torque_limits
        return min_worst_ratio(terms.g, terms.J_contacts, terms.load_per_kg, mass, lim, self.mu)

    def _max_mass(self, terms: StaticTerms) -> float:
        lim = self.desc.torque_limits
        return max_payload(terms.g, terms.J_contacts, terms.load_per_kg, lim, self.mu)

    def _shift_for_com(
        self, terms_at: Callable[[float], StaticTerms], mass: float, x_goal: float, s_max: float
    ) -> float:
        """The shift in [0, s_max] whose combined CoM is at `x_goal` along x, or the nearer
        end of the range (the CoM moves back monotonically with the shift: regula falsi,
        Illinois variant)."""
        a, b = 0.0, s_max
        fa = self._com_x(terms_at(a), mass) - x_goal
        if fa <= 0.0 or s_max <= 0.0:
            return a
        fb = self._com_x(terms_at(b), mass) - x_goal
        if fb >= 0.0:
            return b
        side = 0
        s = a
        for _ in range(40):
            s = (a * fb - b * fa) / (fb - fa)
            fs = self._com_x(terms_at(s), mass) - x_goal
            if abs(fs) < 1e-5 or b - a < SHIFT_TOL / 4:
                break
            if fs > 0.0:
                a, fa = s, fs
                if side == 1:
                    fb /= 2.0
                side = 1
            else:
                b, fb = s, fs
                if side == -1:
                    fa /= 2.0
                side = -1
        return s

    def _terms_function(
        self, pose: HeldPose
    ) -> tuple[Callable[[float], StaticTerms], tuple[float, ...], float]:
        """The statics terms as a function of the shift (memoised), the hands' residuals and
        the reach margin: the arms do not depend on the shift."""
        arms_q, residual, reach = self.postures.arms(pose)
        memo: dict[float, StaticTerms] = {}

        def terms_at(shift: float) -> StaticTerms:
            key = round(shift, 9)
            if key not in memo:
                memo[key] = self.postures.terms(arms_q, pose, shift)
            return memo[key]

        return terms_at, residual, reach

    def ratio_at_centre(self, pose: HeldPose, mass: float) -> float:
        """Worst torque ratio with the shift that puts the combined CoM at the middle of the
        support (inf: not balanced there): an upper bound of `analyse(...).torque_ratio`,
        cheap enough for every compile (one linear programme; memoised)."""
        _check_mass(mass)
        key = (pose, mass)
        if key not in self._centre_ratios:
            terms_at, _, _ = self._terms_function(pose)
            s_max = self.leg_reach(pose.trunk_height)
            s = self._shift_for_com(terms_at, mass, 0.5 * sum(self.support_x), s_max)
            solved = self._solve(terms_at(s), mass)
            if len(self._centre_ratios) > 4096:
                self._centre_ratios.clear()
            self._centre_ratios[key] = math.inf if solved is None else solved.ratio
        return self._centre_ratios[key]

    def analyse(self, pose: HeldPose, mass: float) -> StaticAnalysis:
        """The full static analysis of `pose` holding `mass` kg (module docstring)."""
        _check_mass(mass)
        terms_at, residual, reach = self._terms_function(pose)
        s_max = self.leg_reach(pose.trunk_height)
        x_back, x_front = self.support_x
        s_lo = self._shift_for_com(terms_at, mass, x_front, s_max)
        s_hi = self._shift_for_com(terms_at, mass, x_back, s_max)
        s_mid = self._shift_for_com(terms_at, mass, 0.5 * (x_back + x_front), s_max)
        inside = any(
            x_back - 1e-6 <= self._com_x(terms_at(s), mass) <= x_front + 1e-6 for s in (s_lo, s_hi)
        )
        shift_range = (s_lo, s_hi) if inside else None

        def ratio(s: float) -> float:
            solved = self._solve(terms_at(s), mass)
            return 1e6 if solved is None else solved.ratio

        # The ratio is often flat over the balanced range (hip pitch carries the upper body's
        # moment wherever the hips are): keep the centring shift unless another is better.
        best_s, best = s_mid, ratio(s_mid)
        if shift_range is not None and s_hi - s_lo > SHIFT_TOL:
            found = minimize_scalar(
                ratio, bounds=(s_lo, s_hi), method="bounded", options={"xatol": SHIFT_TOL}
            )
            if float(found.fun) < best - RATIO_TIE:
                best_s = float(found.x)
        terms = terms_at(best_s)
        solved = self._solve(terms, mass)
        x_com = self._com_x(terms, mass)
        lim = self.desc.torque_limits
        return StaticAnalysis(
            mass=mass,
            balanced=solved is not None,
            torque_ratio=math.inf if solved is None else solved.ratio,
            joint=""
            if solved is None
            else self.desc.joint_names[int(np.argmax(abs(solved.tau) / lim))],
            com_margin=min(x_com - x_back, x_front - x_com),
            com_x=x_com,
            support_x=self.support_x,
            reach_margin=reach,
            reach_residual=residual,
            shift=best_s,
            shift_max=s_max,
            shift_range=shift_range,
            payload_limit=self._payload_limit(terms_at, s_max),
            tau=np.full(len(lim), math.nan) if solved is None else solved.tau,
            f_contacts=np.full((len(self.postures.r_points), 3), math.nan)
            if solved is None
            else solved.f.reshape(-1, 3),
            q=terms.q,
        )

    def payload_limit(self, pose: HeldPose) -> float:
        """The largest mass (kg) the pose holds with every torque ratio <= 1 (module
        docstring): the best over the shift range of one linear programme each."""
        terms_at, _, _ = self._terms_function(pose)
        return self._payload_limit(terms_at, self.leg_reach(pose.trunk_height))

    def _payload_limit(self, terms_at: Callable[[float], StaticTerms], s_max: float) -> float:
        """A coarse scan of the shift range, then a bounded search around its best point."""
        if s_max <= 0.0:
            return self._max_mass(terms_at(0.0))
        grid = np.linspace(0.0, s_max, LIMIT_SCAN)
        masses = [self._max_mass(terms_at(float(s))) for s in grid]
        k = int(np.argmax(masses))
        if not math.isfinite(masses[k]):
            return math.inf
        lo, hi = float(grid[max(k - 1, 0)]), float(grid[min(k + 1, LIMIT_SCAN - 1)])
        found = minimize_scalar(
            lambda s: -self._max_mass(terms_at(s)),
            bounds=(lo, hi),
            method="bounded",
            options={"xatol": SHIFT_TOL},
        )
        return max(masses[k], -float(found.fun))


def _check_mass(mass: float) -> None:
    if not (mass >= 0.0 and math.isfinite(mass)):
        raise ValueError(f"mass must be a finite non-negative number of kg, got {mass}")


@cache
def static_model(robot: str) -> StaticModel:
    """The `StaticModel` of a robot name or robot.yaml path, built once per process."""
    return StaticModel(load_robot_description(robot))
