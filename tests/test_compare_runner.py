"""run_variants: spawn-based worker processes give the same runs as in-process ones, report
progress per variant and write one log per variant."""

from __future__ import annotations

from pathlib import Path

import pytest
from compare_fixtures import SHORT_STAND

from locoplan.compare import Variant, default_jobs, run_variants
from locoplan.log.reader import read_log
from locoplan.scenario import load_scenario

# Wall-clock figures differ between two runs of the same simulation; the rest must not.
TIMING_KEYS = {"wall_time", "real_time_factor", "mpc_solve_ms", "wbc_solve_ms", "log"}

VARIANTS = (
    Variant("external-force", "dynamic", "external-force", "short-stand-external-force"),
    Variant("combined", "dynamic", "combined", "short-stand-combined"),
)


def test_default_jobs_is_at_most_two() -> None:
    assert 1 <= default_jobs() <= 2


def test_jobs_must_be_positive(tmp_path: Path) -> None:
    scenario = load_scenario("<test>", SHORT_STAND)
    with pytest.raises(ValueError, match="jobs must be >= 1"):
        run_variants(scenario, SHORT_STAND, VARIANTS, tmp_path, jobs=0)


@pytest.mark.closed_loop
def test_parallel_runs_equal_sequential_runs(tmp_path: Path) -> None:
    scenario = load_scenario("<test>", SHORT_STAND)
    seen: dict[str, float] = {}

    def progress(label: str, t: float, total: float) -> None:
        assert total == pytest.approx(1.0)  # the script's end
        seen[label] = max(seen.get(label, 0.0), t)

    parallel = run_variants(
        scenario, SHORT_STAND, VARIANTS, tmp_path / "par", jobs=2, progress=progress
    )
    sequential = run_variants(scenario, SHORT_STAND, VARIANTS, tmp_path / "seq", jobs=1)
    assert [o.label for o in parallel] == ["external-force", "combined"]
    # Worker progress reaches the parent: both runs reported past half their time.
    assert set(seen) == {"external-force", "combined"}
    assert min(seen.values()) > 0.5
    for p, s in zip(parallel, sequential, strict=True):
        assert p.error is None and p.metrics is not None and s.metrics is not None
        assert {k: v for k, v in p.metrics.items() if k not in TIMING_KEYS} == {
            k: v for k, v in s.metrics.items() if k not in TIMING_KEYS
        }
        assert p.trace is not None and s.trace is not None
        assert p.trace.t.size == s.trace.t.size
        assert p.passed
        assert p.log_path == tmp_path / "par" / f"{p.variant.log_name}.mcap"
        log = read_log(p.log_path)
        assert log.complete and log.metrics is not None
        assert log.metrics["model"] == p.variant.model
