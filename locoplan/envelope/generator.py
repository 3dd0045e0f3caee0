"""Seeded task scripts over issue 12's envelope, one family at a time or as a mixed suite.

`generate(family, rng, index)` draws one script of a family; `generate_suite(n, seed)` draws
`n` scripts mixing the families in SUITE_SHARES, deterministically for a seed. Both draw
HECTOR's envelope unless given another robot's ranges (`ranges.envelope_ranges(robot)`:
heights, distances, masses and gait limits at that robot's scale); its scripts then say
`robot: <name>`. Every script
is YAML of format version 1 with `expect: {no_fall: true, max_torque_ratio: 1.0}` (and
`placed` for the families that place an object), a `gait`, an `end` 1 s after its last task,
and a scene in which nothing overlaps: see the family modules (`transfer`, `carry`,
`motion`) for what each draws, and `ranges` for the ranges themselves.

Where the scripts differ from a plain uniform draw over issue 12's table, because the scene
must make physical sense (a draw that breaks one of these is drawn again):
- walk-carry: the walk goes straight ahead after the turn, and the table the box came from
  must stay 0.15 m clear of the robot's path, so turns under about 55 deg never occur
  (accepted turns span 56-90 deg);
- side-carry: the table and the platform stand side by side, so for steps under ~0.31 m
  they are narrower than 0.30 m across the step (down to the box's width + 3 / 5 cm);
- conveyors are long enough along the belt (up to ~1.8 m) that the placed box is still on
  the belt at `end`, whatever the belt speed;
- turns and walks last at least one gait period (a 30 deg turn at 65 deg/s would be 0.46 s).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from locoplan.envelope.carry import side_carry, standing_hold, walk_carry
from locoplan.envelope.compose import Doc, Draw, NoLayout, script_text
from locoplan.envelope.motion import locomotion, throw
from locoplan.envelope.ranges import HECTOR_RANGES, EnvelopeRanges, envelope_ranges
from locoplan.envelope.transfer import transfer
from locoplan.scenario.model import Scenario

Family = Callable[[Draw, str], Doc]

_FAMILIES: dict[str, Family] = {
    "transfer": transfer,
    "standing-hold": standing_hold,
    "walk-carry": walk_carry,
    "side-carry": side_carry,
    "locomotion": locomotion,
    "throw": throw,
}

FAMILIES: tuple[str, ...] = tuple(_FAMILIES)

# Share of each family in a suite (issue 12's mix of 80 scripts, rounded: transfer 24,
# standing hold 12, walk-carry 12, side-carry 8, locomotion 16, throw 8).
SUITE_SHARES: dict[str, float] = {
    "transfer": 0.30,
    "standing-hold": 0.15,
    "walk-carry": 0.15,
    "side-carry": 0.10,
    "locomotion": 0.20,
    "throw": 0.10,
}

# Draws of one script before giving up (a family redraws when its scene does not fit;
# the worst, walk-carry, needs about three on average).
MAX_ATTEMPTS = 1000


@dataclass(frozen=True, slots=True)
class GeneratedScript:
    """One generated task script: its `name` (also the scenario's), `family` and YAML `text`."""

    name: str
    family: str
    text: str


def generate(
    family: str,
    rng: np.random.Generator,
    index: int,
    ranges: EnvelopeRanges = HECTOR_RANGES,
) -> GeneratedScript:
    """Draw one script of `family` (one of FAMILIES) from `rng`, named `<family>-<index>`,
    over `ranges` (HECTOR's unless given)."""
    try:
        build = _FAMILIES[family]
    except KeyError:
        raise ValueError(f"unknown family {family!r}; known: {', '.join(FAMILIES)}") from None
    name = f"{family}-{index:03d}"
    draw = Draw(rng, ranges)
    for _ in range(MAX_ATTEMPTS):
        try:
            doc = build(draw, name)
        except NoLayout:
            continue
        return GeneratedScript(name, family, script_text(_with_robot(doc, ranges.robot)))
    raise RuntimeError(f"no {family} layout found in {MAX_ATTEMPTS} draws")


def _with_robot(doc: Doc, robot: str) -> Doc:
    """The script with `robot: <robot>` after its description, unless `robot` is the format's
    default robot (whose scripts say nothing)."""
    if robot == Scenario.model_fields["robot"].default:
        return doc
    out: Doc = {}
    for key, value in doc.items():
        out[key] = value
        if key == "description":
            out["robot"] = robot
    return out


def suite_counts(n: int, families: Sequence[str]) -> dict[str, int]:
    """How many scripts of each family a suite of `n` holds: SUITE_SHARES renormalised over
    `families`, by largest remainder, with at least one of each when n >= len(families)."""
    shares = np.array([SUITE_SHARES[f] for f in families], dtype=float)
    exact = n * shares / shares.sum()
    counts = np.floor(exact).astype(int)
    for i in np.argsort(-(exact - counts), kind="stable")[: n - int(counts.sum())]:
        counts[i] += 1
    if n >= len(families):
        while (counts == 0).any():
            counts[int(np.argmax(counts))] -= 1
            counts[int(np.argmin(counts))] += 1
    return {f: int(c) for f, c in zip(families, counts, strict=True)}


def _interleave(counts: dict[str, int]) -> list[str]:
    """The families in a round-robin order weighted by their counts (smooth weighted round
    robin), so that any prefix of the suite is mixed like the whole."""
    total = sum(counts.values())
    current = dict.fromkeys(counts, 0)
    order = []
    for _ in range(total):
        for f, c in counts.items():
            current[f] += c
        best = max(current, key=lambda f: current[f])
        current[best] -= total
        order.append(best)
    return order


def generate_suite(
    n: int, seed: int, families: Sequence[str] | None = None, robot: str | None = None
) -> list[GeneratedScript]:
    """`n` scripts mixing `families` (default all) in SUITE_SHARES, each family at least
    once when n allows, for `robot` (a robot name or robot.yaml path: `envelope_ranges`;
    None: HECTOR's table as written). The k-th script of a family is drawn from its own
    generator seeded with (seed, family, k), so it stays the same when `n` or the other
    families change."""
    ranges = HECTOR_RANGES if robot is None else envelope_ranges(robot)
    chosen = list(families) if families else list(FAMILIES)
    for f in chosen:
        if f not in _FAMILIES:
            raise ValueError(f"unknown family {f!r}; known: {', '.join(FAMILIES)}")
    chosen = list(dict.fromkeys(chosen))
    counts = suite_counts(n, chosen)
    seen = dict.fromkeys(chosen, 0)
    scripts = []
    for family in _interleave(counts):
        k = seen[family]
        seen[family] += 1
        rng = np.random.default_rng([seed, FAMILIES.index(family), k])
        scripts.append(generate(family, rng, k, ranges))
    return scripts
