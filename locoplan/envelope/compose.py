"""Building blocks of the generated scripts: gridded draws, rate-bounded durations, a table
with an object on it, a drop target, and the YAML writer.

Every draw is uniform on a grid (times 0.01 s, lengths 1 mm, angles 0.1 deg, masses 0.01
kg) over an inclusive range of `locoplan.envelope.ranges`, so what is written is inside the
range exactly, not only up to rounding.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from locoplan.envelope import ranges as rg
from locoplan.envelope.geometry import Rect, layout_ok
from locoplan.plan.profiles import peak_rate
from locoplan.scenario.feasibility import ceil_time, turn_rate_limit, walk_speed_limit

Doc = dict[str, Any]


class NoLayout(Exception):
    """The draws so far admit no sensible scene: the family draws its script again."""


def rt(x: float) -> float:
    """A time on the 0.01 s grid."""
    return round(x + 0.0, 2)


def within_gait(duration: float, amount: float, gait_limit: float) -> float:
    """`duration` (s) lengthened by 0.01 s steps until the planned peak rate of `amount` is
    within `gait_limit`."""
    while peak_rate(amount, duration) > gait_limit + 1e-9:
        duration = rt(duration + 0.01)
    return duration


def turn_limit_deg(d: Draw, period: float) -> float:
    """The feasibility check's turn rate limit (deg/s) at a gait `period`, for the robot of
    `d`'s ranges."""
    return math.degrees(turn_rate_limit(period, d.r.hip_yaw_range))


def walk_limit(d: Draw, period: float) -> float:
    """The feasibility check's walk speed limit (m/s) at a gait `period`, for the robot of
    `d`'s ranges."""
    return walk_speed_limit(period, d.r.walk_stride)


def fits(
    d: Draw, fixtures: Sequence[Rect], path: Sequence[Sequence[float]], loose: Sequence[Rect] = ()
) -> bool:
    """`layout_ok` with the robot's radius (`d`'s ranges)."""
    return layout_ok(fixtures, path, loose, robot_radius=d.r.robot_radius)


def rl(x: float) -> float:
    """A length on the 1 mm grid."""
    return round(x + 0.0, 3) + 0.0


def wrap_deg(a: float) -> float:
    """An angle in (-180, 180], on the 0.1 deg grid."""
    a = math.fmod(a, 360.0)
    if a <= -180.0:
        a += 360.0
    elif a > 180.0:
        a -= 360.0
    return round(a, 1) + 0.0


class Draw:
    """Uniform draws on grids from one numpy Generator, over the ranges of one robot (`r`:
    the robot-dependent ones; HECTOR's by default)."""

    def __init__(self, rng: np.random.Generator, ranges: rg.EnvelopeRanges = rg.HECTOR_RANGES):
        self.rng = rng
        self.r = ranges

    def grid(self, lo: float, hi: float, step: float) -> float:
        """Uniform over the multiples of `step` in [lo, hi] (at least one must exist)."""
        k_lo = math.ceil(lo / step - 1e-9)
        k_hi = math.floor(hi / step + 1e-9)
        if k_hi < k_lo:
            raise NoLayout(f"empty range [{lo}, {hi}]")
        k = int(self.rng.integers(k_lo, k_hi + 1))
        digits = max(0, -math.floor(math.log10(step) + 1e-9))
        return round(k * step, digits) + 0.0

    def time(self, lo: float, hi: float) -> float:
        return self.grid(lo, hi, 0.01)

    def length(self, lo: float, hi: float, step: float = 0.001) -> float:
        return self.grid(lo, hi, step)

    def angle(self, lo: float, hi: float) -> float:
        return self.grid(lo, hi, 0.1)

    def mass(self, r: rg.Range) -> float:
        return self.grid(r[0], r[1], 0.01)

    def speed(self, lo: float, hi: float) -> float:
        return self.grid(lo, hi, 0.01)

    def sign(self) -> float:
        return 1.0 if self.rng.random() < 0.5 else -1.0

    def chance(self, p: float) -> bool:
        return bool(self.rng.random() < p)

    def choice(self, options: Sequence[str]) -> str:
        return options[int(self.rng.integers(len(options)))]

    def duration(self, amount: float, max_rate: float, period: float, gait_limit: float) -> float:
        """How long a task covering `amount` (deg or m) takes: `amount` over a rate drawn
        from [RATE_FLOOR x max_rate, max_rate], rounded up to 0.01 s, at least one gait
        `period`, and long enough that its planned peak rate (the trunk's cruise profile) is
        within `gait_limit` (the feasibility check's, same unit per s)."""
        rate = float(self.rng.uniform(rg.RATE_FLOOR * max_rate, max_rate))
        d = max(abs(amount) / rate, period)
        d = ceil_time(d)
        while abs(amount) / d > max_rate + 1e-9:
            d = rt(d + 0.01)
        return within_gait(d, amount, gait_limit)

    def manip_gait(self) -> dict[str, float]:
        """Gait of the manipulation families (MANIP_PERIOD, MANIP_SWING, swing <= P/2)."""
        period = self.time(*rg.MANIP_PERIOD)
        swing = self.time(rg.MANIP_SWING[0], min(rg.MANIP_SWING[1], period / 2))
        return {"period": period, "swing": swing}

    def loco_gait(self) -> dict[str, float]:
        """Gait of the locomotion family: LOCO_PERIOD, swing LOCO_SWING_FRACTION of it."""
        period = self.time(*rg.LOCO_PERIOD)
        lo, hi = rg.LOCO_SWING_FRACTION
        swing = self.time(lo * period, hi * period)
        return {"period": period, "swing": swing}


def polar(origin: Sequence[float], r: float, deg: float) -> tuple[float, float]:
    """The point `r` from `origin` in direction `deg`, on the 1 mm grid."""
    a = math.radians(deg)
    return rl(origin[0] + r * math.cos(a)), rl(origin[1] + r * math.sin(a))


def rect_of(spec: Mapping[str, Any]) -> Rect:
    """Footprint of an object or fixture entry (a sphere's is its bounding square)."""
    size = spec["size"]
    if spec.get("shape") == "sphere":
        length = width = 2 * size[0]
    else:
        length, width = size[0], size[1]
    x, y = spec["position"][:2]
    return Rect(x, y, length, width, spec.get("yaw", 0.0))


@dataclass(frozen=True, slots=True)
class Placed:
    """An object resting on its table: the script entries of both."""

    obj: Doc
    table: Doc


def table_with_object(
    d: Draw,
    origin: Sequence[float],
    direction: float,
    mass: float,
    shape: str = "box",
    width: Callable[[float], float] | None = None,
) -> Placed:
    """A table in direction `direction` (deg) from `origin`, facing it, with an object on
    its top: the object's near side NEAR_SIDE from `origin`, the table's near edge
    TABLE_OVERHANG beyond it, top TABLE_TOP high, footprint FIXTURE_SIDE per side (`width`,
    when given, draws the side across the direction from the object's extent across it).
    A box has sides BOX_SIDE (its height on a 2 mm grid so that its centre z = top +
    height / 2 exactly); a sphere BALL_RADIUS."""
    near = d.length(*d.r.near_side)
    top = d.length(*d.r.table_top)
    if shape == "box":
        size = [d.length(*rg.BOX_SIDE), d.length(*rg.BOX_SIDE), d.length(*rg.BOX_SIDE, step=0.002)]
        depth, across, half_h = size[0], size[1], size[2] / 2
        overhang = d.length(*rg.TABLE_OVERHANG)
    else:
        radius = d.length(*rg.BALL_RADIUS)
        size = [radius]
        depth = across = 2 * radius
        half_h = radius
        # the sphere rests on one point under its centre: keep that 1 cm inside the edge
        overhang = d.length(rg.TABLE_OVERHANG[0], min(rg.TABLE_OVERHANG[1], radius - 0.01))
    edge = near + overhang
    table_depth = d.length(max(rg.FIXTURE_SIDE[0], depth - overhang + 0.02), rg.FIXTURE_SIDE[1])
    if width is None:
        table_width = d.length(max(rg.FIXTURE_SIDE[0], across + 0.03), rg.FIXTURE_SIDE[1])
    else:
        table_width = width(across)
    x, y = polar(origin, edge + table_depth / 2, direction)
    table: Doc = {
        "kind": "table",
        "position": [x, y, 0.0],
        "size": [table_depth, table_width, top],
        "yaw": direction,
    }
    ox, oy = polar(origin, near + depth / 2, direction)
    obj: Doc = {
        "shape": shape,
        "size": size,
        "mass": mass,
        "position": [ox, oy, rl(top + half_h)],
        "yaw": direction,
    }
    if shape == "sphere":
        del obj["yaw"]
    return Placed(obj, table)


def target(
    d: Draw,
    origin: Sequence[float],
    direction: float,
    kind: str,
    extent: float,
    travel: float = 0.0,
    width: float | None = None,
) -> Doc:
    """A drop target ahead of `origin` in direction `direction` (deg): near edge
    TARGET_NEAR_EDGE away, top TABLE_TOP, footprint FIXTURE_SIDE per side (`width` across
    the direction when given). A conveyor (belt CONVEYOR_SPEED, along or across the
    direction) is made long enough that an object `extent` long placed on it at its near
    point stays on the belt for `travel` seconds (the time from the drop's start to `end`)."""
    edge = d.length(*d.r.target_near_edge)
    top = d.length(*d.r.table_top)
    lo, hi = rg.FIXTURE_SIDE
    spec: Doc = {"kind": kind}
    if kind != "conveyor":
        depth = d.length(lo, hi)
        across = width if width is not None else d.length(lo, hi)
        yaw, size = direction, [depth, across, top]
        x, y = polar(origin, edge + depth / 2, direction)
    else:
        speed = d.speed(*rg.CONVEYOR_SPEED)
        if d.chance(0.5):  # belt running away from the robot
            need = extent + speed * travel + 0.05
            belt = d.length(max(lo, need), max(hi, need + 0.3))
            across = width if width is not None else d.length(lo, hi)
            yaw, size = direction, [belt, across, top]
            x, y = polar(origin, edge + belt / 2, direction)
        else:  # belt running across, to the left or the right
            need = extent + 2 * (speed * travel + 0.03)
            belt = width if width is not None else d.length(max(lo, need), max(hi, need + 0.3))
            if belt < need:
                raise NoLayout("conveyor too short")
            depth = d.length(lo, hi)
            yaw, size = wrap_deg(direction + 90.0 * d.sign()), [belt, depth, top]
            x, y = polar(origin, edge + depth / 2, direction)
        spec["speed"] = speed
    spec.update(position=[x, y, 0.0], size=size, yaw=yaw)
    return {k: spec[k] for k in ("kind", "position", "size", "yaw", "speed") if k in spec}


# --- YAML text ---

_PLAIN = re.compile(r"^[A-Za-z][A-Za-z0-9_-]*$")
_RESERVED = {"true", "false", "yes", "no", "on", "off", "null", "y", "n"}


def _num(x: float) -> str:
    s = f"{x:.4f}".rstrip("0")
    if s.endswith("."):
        s += "0"
    return "0.0" if s == "-0.0" else s


def flow(value: Any) -> str:
    """One value in YAML flow style (floats always with a decimal point)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return _num(value)
    if isinstance(value, str):
        plain = _PLAIN.match(value) and value.lower() not in _RESERVED
        return value if plain else json.dumps(value)
    if isinstance(value, Mapping):
        return "{" + ", ".join(f"{k}: {flow(v)}" for k, v in value.items()) + "}"
    if isinstance(value, Sequence):
        return "[" + ", ".join(flow(v) for v in value) + "]"
    raise TypeError(f"cannot write {type(value).__name__}")


def script_text(doc: Doc) -> str:
    """The script as YAML in the style of scenarios/: scalars and small mappings on one line,
    one line per object, fixture and task."""
    lines: list[str] = []
    for key, value in doc.items():
        if key in ("objects", "fixtures"):
            lines.append(f"{key}:")
            lines += [f"  {name}: {flow(spec)}" for name, spec in value.items()]
        elif key == "tasks":
            lines.append("tasks:")
            lines += [f"  - {flow(task)}" for task in value]
        else:
            lines.append(f"{key}: {flow(value)}")
    return "\n".join(lines) + "\n"


def expectations(placed: Mapping[str, str] | None = None) -> Doc:
    """`expect: {no_fall: true, max_torque_ratio: 1.0}`, with `placed` when given."""
    expect: Doc = {"no_fall": True, "max_torque_ratio": 1.0}
    if placed:
        expect["placed"] = dict(placed)
    return expect


def end_after(tasks: Sequence[Mapping[str, Any]]) -> float:
    """`end`: the last task's end plus SETTLE."""
    return rt(max(t["start"] + t["duration"] for t in tasks) + rg.SETTLE)
