"""locoplan.envelope: the seeded generator of task scripts over issue 12's envelope.

Fast (no simulation): determinism, the family mix, every script valid for the loader that
`locoplan validate` uses, the envelope's ranges read back from the loaded scripts, and scenes
in which nothing overlaps (footprints as yawed rectangles, the robot as a 0.15 m circle).
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np
import pytest

from locoplan.envelope import FAMILIES, GeneratedScript, generate, generate_suite, suite_counts
from locoplan.envelope import ranges as rg
from locoplan.envelope.geometry import (
    ROBOT_RADIUS,
    Rect,
    path_clearance,
    rects_apart,
    segment_rect_distance,
)
from locoplan.scenario import (
    DropTask,
    FixtureSpec,
    ObjectSpec,
    PickTask,
    Scenario,
    StandTask,
    StepTask,
    ThrowTask,
    TurnTask,
    WalkTask,
    load_scenario_file,
)

TOL_LEN = 0.0015  # m: positions are written to 1 mm, distances computed from them
EPS = 1e-9


@cache
def suite() -> tuple[tuple[GeneratedScript, Scenario], ...]:
    """300 scripts over five seeds, each loaded as `locoplan validate` loads it."""
    out = []
    for seed in range(5):
        for script in generate_suite(60, seed):
            loaded = load_scenario_file(f"{script.family}/{script.name}.yaml", script.text)
            out.append((script, loaded.scenario))
    return tuple(out)


def of(family: str) -> list[Scenario]:
    return [s for g, s in suite() if g.family == family]


def tasks_of(s: Scenario, kind: type) -> list:
    return [t for t in s.tasks if isinstance(t, kind)]


def rect(spec: FixtureSpec | ObjectSpec) -> Rect:
    if isinstance(spec, ObjectSpec) and spec.shape == "sphere":
        r = spec.size[0]
        return Rect(spec.position[0], spec.position[1], 2 * r, 2 * r, 0.0)
    return Rect(spec.position[0], spec.position[1], spec.size[0], spec.size[1], spec.yaw)


def unit(deg: float) -> np.ndarray:
    return np.array([math.cos(math.radians(deg)), math.sin(math.radians(deg))])


def near_edge(spec: FixtureSpec | ObjectSpec, at: np.ndarray, heading: float) -> float:
    """How far ahead of `at` (facing `heading`) the footprint's nearest side is."""
    return float(min((rect(spec).corners - at) @ unit(heading)))


def start(s: Scenario) -> tuple[np.ndarray, float]:
    return np.asarray(s.robot_start.position, dtype=float), s.robot_start.yaw


def path_of(s: Scenario) -> tuple[list[np.ndarray], float]:
    """The trunk's planned positions at the walks' ends, and its final yaw."""
    p, yaw = start(s)
    points = [p]
    for t in sorted(s.tasks, key=lambda t: t.start):
        if isinstance(t, WalkTask):
            c, si = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
            dx, dy = t.distance
            p = p + np.array([c * dx - si * dy, si * dx + c * dy])
            points.append(p)
            yaw += t.angle
        elif isinstance(t, TurnTask):
            yaw += t.angle
    return points, yaw


def on_grid(x: float, step: float) -> bool:
    return abs(x / step - round(x / step)) < 1e-6


# --- the suite ---


def test_a_seed_gives_the_same_scripts_and_another_seed_others() -> None:
    a = generate_suite(24, 11)
    assert a == generate_suite(24, 11)
    assert [s.text for s in a] != [s.text for s in generate_suite(24, 12)]
    rng1, rng2 = np.random.default_rng(5), np.random.default_rng(5)
    assert generate("transfer", rng1, 3) == generate("transfer", rng2, 3)


@pytest.mark.parametrize("n", [6, 7, 9, 12, 20])
def test_every_family_appears_once_there_are_six_scripts(n: int) -> None:
    scripts = generate_suite(n, 3)
    assert len(scripts) == n
    assert {s.family for s in scripts} == set(FAMILIES)
    assert len({s.name for s in scripts}) == n


def test_the_mix_follows_the_issue_s_shares() -> None:
    assert suite_counts(100, FAMILIES) == {
        "transfer": 30,
        "standing-hold": 15,
        "walk-carry": 15,
        "side-carry": 10,
        "locomotion": 20,
        "throw": 10,
    }
    assert sum(suite_counts(37, FAMILIES).values()) == 37
    only = generate_suite(5, 0, ["throw", "side-carry"])
    assert {s.family for s in only} == {"throw", "side-carry"}
    with pytest.raises(ValueError, match="unknown family"):
        generate_suite(3, 0, ["juggle"])


def test_a_family_s_scripts_do_not_change_with_n() -> None:
    small = [s for s in generate_suite(10, 4) if s.family == "transfer"]
    large = [s for s in generate_suite(40, 4) if s.family == "transfer"]
    assert large[: len(small)] == small


def test_every_script_is_valid_and_written_as_the_brief_asks() -> None:
    assert len(suite()) == 300
    for script, s in suite():
        assert s.name == script.name
        assert script.text.startswith("version: 1\n")
        assert s.expect.no_fall is True and s.expect.max_torque_ratio == 1.0
        assert s.gait is not None
        ends = [t.start + t.duration for t in s.tasks]
        assert s.end == pytest.approx(max(ends) + 1.0, abs=EPS), s.name
        for t in s.tasks:
            assert on_grid(t.start, 0.01) and on_grid(t.duration, 0.01), s.name
        specs: list[ObjectSpec | FixtureSpec] = [*s.objects.values(), *s.fixtures.values()]
        for spec in specs:
            assert all(on_grid(x, 0.001) for x in [*spec.position, *spec.size]), s.name
        for obj, fixture in (s.expect.placed or {}).items():
            drops = [t for t in tasks_of(s, DropTask) if t.object == obj]
            assert drops and drops[-1].onto == fixture


def test_gaits_are_in_range() -> None:
    for script, s in suite():
        assert s.gait is not None
        period, swing = s.gait.period, s.gait.swing
        if script.family == "locomotion":
            assert 0.3 - EPS <= period <= 0.5 + EPS
            assert 0.4 * period - 0.005 <= swing <= 0.5 * period + EPS
        else:
            assert 0.35 - EPS <= period <= 0.45 + EPS
            assert 0.15 - EPS <= swing <= 0.2 + EPS


# --- the envelope, family by family ---

MASSES = {
    "transfer": rg.TRANSFER_MASS,
    "standing-hold": rg.HOLD_MASS,
    "walk-carry": rg.WALK_CARRY_MASS,
    "side-carry": rg.SIDE_MASS,
    "throw": rg.THROW_MASS,
}


def test_masses_objects_and_manipulation_durations_are_in_range() -> None:
    for script, s in suite():
        for obj in s.objects.values():
            lo, hi = MASSES[script.family]
            assert lo - EPS <= obj.mass <= hi + EPS, script.name
            if obj.shape == "box":
                assert all(0.10 - EPS <= x <= 0.25 + EPS for x in obj.size), script.name
            else:
                assert 0.05 - EPS <= obj.size[0] <= 0.10 + EPS, script.name
        for t in [*tasks_of(s, PickTask), *tasks_of(s, DropTask), *tasks_of(s, ThrowTask)]:
            assert 0.8 - EPS <= t.duration <= 1.5 + EPS, script.name


def test_objects_rest_on_their_table_near_the_robot() -> None:
    for script, s in suite():
        if not s.objects:
            continue
        p, yaw = start(s)
        (obj,) = s.objects.values()
        table = s.fixtures["table"]
        heading = table.yaw if obj.shape == "box" else yaw
        half_h = obj.size[2] / 2 if obj.shape == "box" else obj.size[0]
        assert obj.position[2] == pytest.approx(table.size[2] + half_h, abs=EPS), script.name
        assert rect(table).distance_to_point(obj.position[:2]) == 0.0, script.name
        near = near_edge(obj, p, heading)
        assert 0.20 - TOL_LEN <= near <= 0.28 + TOL_LEN, script.name
        beyond = near_edge(table, p, heading) - near
        assert -TOL_LEN <= beyond <= 0.04 + TOL_LEN, script.name
        assert 0.40 - EPS <= table.size[2] <= 0.55 + EPS
        if obj.shape == "box":
            assert obj.yaw == table.yaw  # facing the robot at the pick
            offset = (np.asarray(obj.position[:2]) - p) @ unit(heading + 90)
            assert abs(offset) <= TOL_LEN, script.name


def test_targets_lie_ahead_of_the_robot_at_the_drop() -> None:
    for script, s in suite():
        for drop in tasks_of(s, DropTask):
            if script.family == "standing-hold":
                assert drop.onto == "table"
                continue
            points, final_yaw = path_of(s)
            assert drop.onto is not None
            goal = s.fixtures[drop.onto]
            edge = near_edge(goal, points[-1], final_yaw)
            assert 0.15 - TOL_LEN <= edge <= 0.25 + TOL_LEN, script.name
            assert 0.40 - EPS <= goal.size[2] <= 0.55 + EPS
            if goal.kind == "conveyor":
                assert goal.speed is not None and 0.0 <= goal.speed <= 0.3 + EPS


def test_transfer_turns_and_timing_follow_the_envelope() -> None:
    scenarios = of("transfer")
    assert len(scenarios) == 90
    kinds = set()
    for s in scenarios:
        turn1, turn2 = tasks_of(s, TurnTask)
        (pick,) = tasks_of(s, PickTask)
        (drop,) = tasks_of(s, DropTask)
        assert 30 - EPS <= abs(turn1.angle) <= 180 + EPS
        assert 60 - EPS <= abs(turn2.angle) <= 180 + EPS
        assert turn1.angle * turn2.angle < 0
        for t in (turn1, turn2):
            assert abs(t.angle) / t.duration <= 65 + EPS
        assert turn1.start + turn1.duration / 2 - EPS <= pick.start <= turn1.end + EPS
        assert turn2.start + turn2.duration / 2 - EPS <= drop.start <= turn2.end + EPS
        assert pick.end <= drop.start + EPS
        table = s.fixtures["table"]
        assert table.yaw == pytest.approx(turn1.angle if abs(turn1.angle) < 180 else 180.0)
        assert drop.onto is not None
        kinds.add(s.fixtures[drop.onto].kind)
    assert kinds == {"platform", "conveyor"}


def test_walk_carry_side_carry_and_hold_follow_the_envelope() -> None:
    for s in of("walk-carry"):
        (pick,) = tasks_of(s, PickTask)
        (walk,) = tasks_of(s, WalkTask)
        for turn in tasks_of(s, TurnTask):
            assert abs(turn.angle) <= 90 + EPS
            assert abs(turn.angle) / turn.duration <= 65 + EPS
            assert pick.end - 0.3 - EPS <= turn.start  # during the pick's last part at most
        assert walk.distance[1] == 0.0 and 0.3 - EPS <= walk.distance[0] <= 1.5 + EPS
        assert walk.distance[0] / walk.duration <= 0.3 + EPS
    for s in of("side-carry"):
        (walk,) = tasks_of(s, WalkTask)
        assert walk.distance[0] == 0.0 and 0.3 - EPS <= abs(walk.distance[1]) <= 0.6 + EPS
        assert abs(walk.distance[1]) / walk.duration <= 0.25 + EPS
    for s in of("standing-hold"):
        (pick,) = tasks_of(s, PickTask)
        holds = [t for t in tasks_of(s, StandTask) if t.start >= pick.end - EPS]
        (drop,) = tasks_of(s, DropTask)
        assert len(holds) == 1 and 2.0 - EPS <= holds[0].duration <= 6.0 + EPS
        assert drop.start == pytest.approx(holds[0].end)


def test_locomotion_and_throw_follow_the_envelope() -> None:
    kinds = set()
    for s in of("locomotion"):
        assert 2 <= len(s.tasks) <= 4 and not s.objects and not s.fixtures
        for t in s.tasks:
            kinds.add(t.action)
            if isinstance(t, WalkTask):
                length = math.hypot(*t.distance)
                assert length <= 1.5 + TOL_LEN and length / t.duration <= 0.35 + EPS
                assert abs(t.angle) <= 60 + EPS and abs(t.angle) / t.duration <= 90 + EPS
            elif isinstance(t, TurnTask):
                assert abs(t.angle) <= 180 + EPS and abs(t.angle) / t.duration <= 90 + EPS
    assert kinds == {"walk", "turn", "step"}
    stepping = 0
    for s in of("throw"):
        (throw,) = tasks_of(s, ThrowTask)
        vx, vy, vz = throw.velocity
        assert 1.0 - EPS <= vx <= 2.0 + EPS and abs(vy) <= 0.3 + EPS and 0.5 - EPS <= vz <= 1.5
        for step in tasks_of(s, StepTask):
            stepping += 1
            assert step.start < throw.start and step.end > throw.end
    assert 0 < stepping < len(of("throw"))


# --- no overlaps ---


def test_no_fixture_overlaps_another_or_the_robot_s_path() -> None:
    for script, s in suite():
        fixtures = list(s.fixtures.values())
        for i, a in enumerate(fixtures):
            for b in fixtures[i + 1 :]:
                assert rects_apart(rect(a), rect(b), 0.005), script.name
        points, _ = path_of(s)
        for f in fixtures:
            assert path_clearance(rect(f), points) >= ROBOT_RADIUS - 1e-6, script.name
        for obj in s.objects.values():
            assert rect(obj).distance_to_point(points[0]) >= ROBOT_RADIUS - 1e-6
            for name, f in s.fixtures.items():
                if name != "table":
                    assert rects_apart(rect(obj), rect(f)), script.name


def test_the_overlap_geometry_itself() -> None:
    square = Rect(0.0, 0.0, 1.0, 1.0, 0.0)
    assert not rects_apart(square, Rect(0.9, 0.0, 1.0, 1.0, 0.0))
    assert rects_apart(square, Rect(1.05, 0.0, 1.0, 1.0, 0.0), 0.04)
    assert not rects_apart(square, Rect(1.05, 0.0, 1.0, 1.0, 0.0), 0.06)
    # a diamond whose corner pokes into the square's side, and one that stays clear
    assert not rects_apart(square, Rect(1.2, 0.0, 1.0, 1.0, 45.0))
    assert rects_apart(square, Rect(1.25, 0.0, 1.0, 1.0, 45.0))
    assert segment_rect_distance(square, (-2.0, 0.0), (2.0, 0.0)) == 0.0
    assert segment_rect_distance(square, (-2.0, 0.8), (2.0, 0.8)) == pytest.approx(0.3)
    assert segment_rect_distance(square, (1.0, 1.0), (2.0, 2.0)) == pytest.approx(
        math.hypot(0.5, 0.5)
    )
    turned = Rect(0.5, 0.0, 0.4, 0.4, 30.0)
    assert path_clearance(turned, [(0.0, 0.0)]) == turned.distance_to_point((0.0, 0.0))
    assert path_clearance(turned, [(0.0, 0.0), (1.0, 0.0)]) == 0.0
    assert path_clearance(turned, [(0.0, -0.5), (1.0, -0.5)]) > 0.0
