"""A fixed sample of generated envelope scripts, one per family, run closed loop in MuJoCo and
asserted from the simulation state (no fall, torques within limits, objects where expected).

This is a regression sample, not the success-rate measurement: `benchmarks/envelope.py`
measures the envelope (README, "Envelope"). The scripts are drawn by `generate_suite(80, 1)`
(seed 1, the seed the planner was tuned on) and are ones that succeeded when this test was
written; a change that makes one of them fall is a regression to look at in its log.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from locoplan.envelope import generate_suite
from locoplan.scenario import load_scenario_file
from locoplan.sim.run import RunOptions, run_scenario

pytestmark = pytest.mark.closed_loop

SAMPLE = (
    "transfer-000",
    "standing-hold-001",
    "walk-carry-001",
    "side-carry-000",
    "locomotion-001",
    "throw-001",
)


@pytest.fixture(scope="module")
def suite() -> dict[str, str]:
    return {s.name: s.text for s in generate_suite(80, 1)}


@pytest.mark.parametrize("name", SAMPLE)
def test_generated_script_succeeds(tmp_path: Path, suite: dict[str, str], name: str) -> None:
    path = tmp_path / f"{name}.yaml"
    path.write_text(suite[name])
    loaded = load_scenario_file(path)
    result = run_scenario(loaded.scenario, loaded.text, RunOptions(out_dir=tmp_path))
    m = result.metrics
    assert not m["fell"], m["expectations"]
    assert m["peak_torque_ratio"] <= 1.0
    for obj, fixture in (loaded.scenario.expect.placed or {}).items():
        assert m["objects"][obj]["on"] == fixture, m["objects"]
    assert m["passed"], m["expectations"]


DATA = Path(__file__).parent / "data" / "envelope"
# Issue 12's example scripts, all four (walk-carry-6kg since its box is carried close to the
# trunk through the loaded turn and walk: it fell 1.0 s into its walk before; hold-11kg since
# its pick starts with a step nearer, tests/test_step_in.py: it stood and its block was
# "placed" on its table in earlier revisions, but the block never left the table). Success
# includes the pick's `held` check (`locoplan.sim.run._not_held`).
EXAMPLES = [p.stem for p in sorted(DATA.glob("*.yaml"))]


@pytest.mark.parametrize("name", EXAMPLES)
def test_issue_example_succeeds(tmp_path: Path, name: str) -> None:
    loaded = load_scenario_file(DATA / f"{name}.yaml")
    result = run_scenario(loaded.scenario, loaded.text, RunOptions(out_dir=tmp_path))
    m = result.metrics
    assert not m["fell"]
    assert m["peak_torque_ratio"] <= 1.0
    assert m["passed"], m["expectations"]
