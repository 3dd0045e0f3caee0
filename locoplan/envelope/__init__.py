"""Task scripts drawn at random over issue 12's envelope, for `benchmarks/envelope.py` and
the closed-loop sample tests.

`generate(family, rng, index)` -> `GeneratedScript` (name, family, YAML text);
`generate_suite(n, seed, families=None)` -> a deterministic mixed suite; `FAMILIES`.
The ranges are in `locoplan.envelope.ranges`, one constant per row of the issue's table.
"""

from locoplan.envelope.generator import (
    FAMILIES,
    SUITE_SHARES,
    GeneratedScript,
    generate,
    generate_suite,
    suite_counts,
)

__all__ = [
    "FAMILIES",
    "SUITE_SHARES",
    "GeneratedScript",
    "generate",
    "generate_suite",
    "suite_counts",
]
