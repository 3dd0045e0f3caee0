"""compare_scenario closed loop in MuJoCo: identical schedules agree, and the paper's
package-transfer result (issue 6 "must hold") on the repository script and three variants."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from compare_fixtures import SHORT_TURN, package_transfer_yaml, repo_scenario_text

from locoplan.compare import Comparison, compare_scenario, write_compare_json
from locoplan.scenario import Scenario, load_scenario

pytestmark = pytest.mark.closed_loop

# What the issue asks of the package transfer (paper: 1.7 s sooner, up to 30 deg less).
MIN_TIME_SAVED = 1.0  # s
MIN_YAW_REDUCTION = 15.0  # deg


def test_identical_schedules_agree_within_one_mpc_step(tmp_path: Path) -> None:
    scenario = load_scenario("<test>", SHORT_TURN)
    c = compare_scenario(scenario, SHORT_TURN, tmp_path, jobs=1)
    assert c.schedules_identical
    assert c.completion_times_agree is True
    qs, dyn = (o.metrics for o in c.outcomes)
    assert qs is not None and dyn is not None
    # Same plan, same simulation: equal within one MPC step (the contract's tolerance).
    assert abs(qs["completion_time"] - dyn["completion_time"]) <= scenario.mpc.dt
    assert c.schedule_note is not None and c.schedule_note.startswith("schedules identical:")
    assert "agree within one MPC step" in c.schedule_note
    assert c.passed and not c.broke
    path = write_compare_json(c, tmp_path / "compare.json")
    data = json.loads(path.read_text())
    assert list(data) == ["quasi-static", "dynamic"]
    assert data["quasi-static"]["strategy"] == "quasi-static"
    assert data["dynamic"]["strategy"] == "dynamic"
    logs = {Path(data[k]["log"]).name for k in data}
    assert logs == {"short-turn-quasi-static.mcap", "short-turn-dynamic.mcap"}
    assert all((tmp_path / name).stat().st_size > 0 for name in logs)


def _summary(c: Comparison) -> str:
    parts = []
    for o in c.outcomes:
        m = o.metrics or {}
        parts.append(
            f"{o.label}: error={o.error} completed={m.get('completed')} "
            f"t={m.get('completion_time')} yaw={m.get('yaw_difference_deg')} "
            f"fell={m.get('fell')}@{m.get('fall_time')} objects={m.get('objects')} "
            f"torque={m.get('peak_torque_ratio')}"
        )
    return "; ".join(parts)


def _assert_package_transfer_holds(c: Comparison) -> None:
    """Issue 6: dynamic >= 1.0 s sooner, >= 15 deg less pick-to-drop yaw difference; both
    place the package on the conveyor, neither falls, both peak torque ratios <= 1."""
    info = _summary(c)
    assert not c.broke, info
    qs, dyn = c.outcome("quasi-static").metrics, c.outcome("dynamic").metrics
    assert qs is not None and dyn is not None
    for m in (qs, dyn):
        assert not m["fell"], info
        assert m["objects"]["package"]["on"] == "conveyor", info
        assert m["peak_torque_ratio"] <= 1.0, info
        assert m["completed"], info
    assert qs["completion_time"] - dyn["completion_time"] >= MIN_TIME_SAVED, info
    assert qs["yaw_difference_deg"] - dyn["yaw_difference_deg"] >= MIN_YAW_REDUCTION, info


def _compare(scenario: Scenario, text: str, out: Path) -> Comparison:
    return compare_scenario(scenario, text, out, jobs=2)


def test_package_transfer_dynamic_is_faster_with_less_yaw(tmp_path: Path) -> None:
    scenario, text = repo_scenario_text("package-transfer")
    _assert_package_transfer_holds(_compare(scenario, text, tmp_path))


@pytest.mark.parametrize(
    ("side", "mass", "shift"),
    [(-1.0, 3.0, 0.0), (1.0, 2.0, 0.0), (1.0, 2.5, 0.03)],
    ids=["mirrored-table-right", "package-2kg", "fixtures-3cm-further-2.5kg"],
)
def test_package_transfer_variants(tmp_path: Path, side: float, mass: float, shift: float) -> None:
    text = package_transfer_yaml(side, mass, shift)
    scenario = load_scenario("<variant>", text)
    _assert_package_transfer_holds(_compare(scenario, text, tmp_path))
