"""`benchmarks/envelope.py`'s per-run progress line: a script the plan compiler refuses is
"refused" there, as the report counts it, and a broken run is still an "error"."""

from __future__ import annotations

import importlib.util
import io
import sys
from pathlib import Path
from types import ModuleType

from rich.console import Console

from locoplan.batch.job import Outcome

ROOT = Path(__file__).resolve().parents[1]


def _module() -> ModuleType:
    spec = importlib.util.spec_from_file_location(
        "envelope_bench", ROOT / "benchmarks" / "envelope.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    # (Registered first: its dataclasses look their module up in sys.modules.)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_the_progress_line_says_refused_for_a_planner_refusal() -> None:
    bench = _module()
    out = io.StringIO()
    progress = bench._Progress(2, Console(file=out, width=200))
    progress.finished(
        Outcome("a.yaml", "error", message="cannot plan: a.yaml:3:5: infeasible (lift): ...")
    )
    progress.finished(Outcome("b.yaml", "error", message="worker crashed"))
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("[1/2] refused a.yaml"), lines
    assert lines[1].startswith("[2/2] error   b.yaml"), lines
    assert bench.refused_by_planner(Outcome("c.yaml", "error", message="cannot plan: x"))
    assert not bench.refused_by_planner(Outcome("d.yaml", "failed", message="cannot plan: x"))
