"""locoplan.envelope.ranges.envelope_ranges: the envelope at a robot's own scale. HECTOR's is
the issue's table exactly; H1's is derived from its description and static analysis, and its
scripts are valid H1 scripts inside those ranges (no simulation)."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest

from locoplan.envelope import generate_suite
from locoplan.envelope import ranges as rg
from locoplan.envelope.geometry import Rect, path_clearance
from locoplan.plan.robot_geometry import plan_geometry
from locoplan.robot.description import load_robot_description
from locoplan.scenario import Scenario, load_scenario_file

EPS = 1e-9


@cache
def h1_suite() -> tuple[Scenario, ...]:
    """120 H1 scripts over two seeds, each loaded as `locoplan validate` loads it (with H1's
    feasibility limits)."""
    out = []
    for seed in (3, 4):
        for script in generate_suite(60, seed, robot="h1"):
            out.append(load_scenario_file(f"{script.name}.yaml", script.text).scenario)
    return tuple(out)


def test_hector_s_ranges_are_the_table_as_written() -> None:
    assert rg.envelope_ranges("hector") == rg.HECTOR_RANGES
    named = [s.text for s in generate_suite(30, 777, robot="hector")]
    assert named == [s.text for s in generate_suite(30, 777)]
    assert not any("robot:" in text for text in named)


def test_h1_s_ranges_follow_from_its_description_and_statics() -> None:
    r = rg.envelope_ranges("h1")
    desc = load_robot_description("h1")
    geo = plan_geometry(desc)
    # Tables as high above H1's default hands (pelvis 0.98 m + 0.0916 m) as HECTOR's above
    # its own (0.55 m): +0.5216 m.
    lift = 0.98 + geo.hand_default_in_trunk[2] - 0.55
    assert r.table_top == pytest.approx((0.40 + lift, 0.55 + lift), abs=5e-4)
    # The tuck stays below every table (the sphere's top).
    assert 0.98 + geo.hand_tuck_in_trunk[2] + desc.hand_radius < r.table_top[0]
    # Objects and targets keep HECTOR's margin outside the feet: H1's footprint 0.2465 m
    # (HECTOR's 0.1345 m).
    out = geo.footprint_radius - np.hypot(0.09, 0.10)
    assert r.near_side == pytest.approx((0.20 + out, 0.28 + out), abs=5e-4)
    assert r.target_near_edge == pytest.approx((0.15 + out, 0.25 + out), abs=5e-4)
    assert r.robot_radius == pytest.approx(0.15 + out, abs=5e-4)
    # Payload at the carry pose: H1's elbows (18 N m) bound it at about 13 kg, HECTOR's hip
    # pitch at 20.7 kg (shared/robot.md: about 21.6 kg with the hands at 0.58 m).
    h1, hector = rg.carry_payload_limit("h1"), rg.carry_payload_limit("hector")
    assert h1 == pytest.approx(13.0, abs=0.3) and hector == pytest.approx(20.7, abs=0.3)
    assert r.hold_mass == (0.5, pytest.approx(14.0 * h1 / hector, abs=0.01))
    assert r.hold_mass[1] < rg.HOLD_MASS[1] and r.transfer_mass[1] < rg.TRANSFER_MASS[1]
    assert (r.walk_stride, r.hip_yaw_range) == (geo.walk_stride, geo.hip_yaw_range)


def test_h1_scripts_name_h1_and_stay_inside_its_ranges() -> None:
    r = rg.envelope_ranges("h1")
    masses = [r.transfer_mass, r.hold_mass, r.walk_carry_mass, r.side_mass, r.throw_mass]
    hi = max(m[1] for m in masses)
    for s in h1_suite():
        assert s.robot == "h1"
        for obj in s.objects.values():
            assert obj.mass <= hi + EPS, s.name
        start = np.asarray(s.robot_start.position, dtype=float)
        for fx in s.fixtures.values():
            assert r.table_top[0] - EPS <= fx.size[2] <= r.table_top[1] + EPS, s.name
            # nothing nearer the start than H1's disc (its feet's footprint plus HECTOR's
            # margin)
            footprint = Rect(fx.position[0], fx.position[1], fx.size[0], fx.size[1], fx.yaw)
            assert path_clearance(footprint, [start]) >= r.robot_radius - 1e-6, s.name
    holds = [s for s in h1_suite() if s.name.startswith("standing-hold")]
    assert holds and max(o.mass for s in holds for o in s.objects.values()) <= r.hold_mass[1]
