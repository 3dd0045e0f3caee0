"""Outcomes and how failed expectations read (locoplan/batch/job.py)."""

from __future__ import annotations

from locoplan.batch.job import Outcome, failed_expectations


def test_failed_expectations_one_line_each_in_order() -> None:
    metrics = {
        "fall_time": 2.345,
        "expectations": {
            "no_fall": {"ok": False, "value": True, "limit": True},
            "max_torque_ratio": {"ok": False, "value": 0.1288, "limit": 0.001},
            "max_completion_time": {"ok": False, "value": None, "limit": 5.0},
            "placed.package": {"ok": False, "value": "table", "limit": "conveyor"},
            "max_yaw_difference": {"ok": True, "value": 10.0, "limit": 60},
        },
    }
    assert failed_expectations(metrics) == (
        "no_fall: fell at t=2.35 s",
        "max_torque_ratio: peak torque ratio 0.1288 > limit 0.001",
        "max_completion_time: never reached (limit 5)",
        "placed.package: on table, expected conveyor",
    )


def test_outcome_failures_empty_without_metrics() -> None:
    assert Outcome("x", "error", message="boom").failures == ()
    ok = {"expectations": {"no_fall": {"ok": True, "value": False, "limit": True}}}
    assert Outcome("x", "passed", ok).failures == ()
