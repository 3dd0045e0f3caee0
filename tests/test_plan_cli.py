"""`locoplan plan` (cli plan section), the plan table and the plan plot."""

from __future__ import annotations

import json
import struct

from plan_fixtures import SCENARIO_DIR, repo_scenario
from rich.console import Console
from typer.testing import CliRunner

from locoplan.cli import app
from locoplan.plan import compile_plan
from locoplan.report.plan_plot import plot_plan
from locoplan.report.plan_table import plan_table

runner = CliRunner()
PACKAGE = str(SCENARIO_DIR / "package-transfer.yaml")


def _png_size(path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = struct.unpack(">II", data[16:24])
    return width, height


def test_plan_prints_table_and_writes_json_and_png(tmp_path) -> None:
    js, png = tmp_path / "plan.json", tmp_path / "plan.png"
    result = runner.invoke(
        app,
        ["plan", PACKAGE, "--strategy", "quasi-static", "--json", str(js), "--plot", str(png)],
    )
    assert result.exit_code == 0, result.output
    for text in ("pick", "L foot", "R hand", "object package", "final yaw", "total time"):
        assert text in result.output
    data = json.loads(js.read_text())
    assert data["strategy"] == "quasi-static"
    assert data["summary"]["total_time"] == 6.0
    assert [t["action"] for t in data["tasks"]] == ["turn", "pick", "turn", "drop"]
    # a real figure, not an empty canvas: > 20 kB and at least 800 px wide
    assert png.stat().st_size > 20_000
    width, height = _png_size(png)
    assert width >= 800 and height >= 500


def test_plan_bad_inputs_exit_2(tmp_path) -> None:
    result = runner.invoke(app, ["plan", PACKAGE, "--strategy", "fast"])
    assert result.exit_code == 2
    bad = tmp_path / "bad.yaml"
    bad.write_text("version: 1\nname: x\ntasks: []\n")
    result = runner.invoke(app, ["plan", str(bad)])
    assert result.exit_code == 2
    assert "bad.yaml:3" in result.output


def test_plan_table_and_plot_render() -> None:
    plan = compile_plan(repo_scenario("throw"))
    console = Console(record=True, width=140)
    console.print(plan_table(plan))
    text = console.export_text()
    assert "accelerate" in text and "throw" in text and "ball" in text


def test_plot_plan_writes_png(tmp_path) -> None:
    out = plot_plan(compile_plan(repo_scenario("walk-square")), tmp_path / "square.png")
    assert out.exists() and out.stat().st_size > 20_000
