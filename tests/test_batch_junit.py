"""JUnit XML of a batch (locoplan/batch/junit.py), read back with ElementTree."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from locoplan.batch.batch import BatchCase, BatchResult
from locoplan.batch.job import Job, Outcome
from locoplan.batch.junit import junit_xml, metric_properties, write_junit
from locoplan.sim.run import RunOptions

PASSED = {
    "scenario": "ok",
    "peak_torque_ratio": 0.13,
    "fell": False,
    "completion_time": None,
    "peak_torque": {"L_knee": 8.6},
    "final_base": {"position": [0.0, 0.0, 0.6]},
    "expectations": {"no_fall": {"ok": True, "value": False, "limit": True}},
    "passed": True,
}
FAILED = {
    **PASSED,
    "scenario": "tight",
    "expectations": {"max_torque_ratio": {"ok": False, "value": 0.13, "limit": 0.001}},
    "passed": False,
}


def _case(path: str, classname: str = "suite", valid: bool = True) -> BatchCase:
    job = Job(path, Path(path).stem, path, "", RunOptions()) if valid else None
    return BatchCase(path, Path(path), classname, job, None)


def _results() -> list[BatchResult]:
    return [
        BatchResult(
            _case("suite/ok.yaml"), Outcome("suite/ok.yaml", "passed", PASSED, wall_time=2.0)
        ),
        BatchResult(
            _case("suite/sub/tight.yaml", "suite.sub"),
            Outcome("suite/sub/tight.yaml", "failed", FAILED, wall_time=2.5, cached=True),
        ),
        BatchResult(
            _case("suite/bad.yml", valid=False),
            Outcome(
                "suite/bad.yml",
                "error",
                message="suite/bad.yml:4:14: unknown action 'jump'",
                detail="suite/bad.yml:4:14: unknown action 'jump'\nsuite/bad.yml:5:3: more\x01",
            ),
        ),
        BatchResult(_case("suite/z.yaml"), Outcome("suite/z.yaml", "skipped", message="not run")),
    ]  # fmt: skip


def test_one_testcase_per_script_with_counts() -> None:
    root = ET.fromstring(junit_xml(_results()))
    assert root.tag == "testsuites"
    suite = root.find("testsuite")
    assert suite is not None
    counts = [suite.get(k) for k in ("tests", "failures", "errors", "skipped")]
    assert counts == ["4", "1", "1", "1"]
    cases = suite.findall("testcase")
    assert [(c.get("classname"), c.get("name"), c.get("file")) for c in cases] == [
        ("suite", "ok.yaml", "suite/ok.yaml"),
        ("suite.sub", "tight.yaml", "suite/sub/tight.yaml"),
        ("suite", "bad.yml", "suite/bad.yml"),
        ("suite", "z.yaml", "suite/z.yaml"),
    ]
    assert cases[0].get("time") == "2.000"


def test_metrics_are_properties_and_failures_name_the_expectation() -> None:
    cases = ET.fromstring(junit_xml(_results())).iter("testcase")
    ok, tight, bad, skipped = cases
    props = {p.get("name"): p.get("value") for p in ok.iter("property")}
    assert props["peak_torque_ratio"] == "0.13"
    assert props["peak_torque.L_knee"] == "8.6"
    assert props["final_base.position"] == "[0.0, 0.0, 0.6]"
    assert props["completion_time"] == "null"
    assert props["fell"] == "false"
    assert props["status"] == "passed" and props["cached"] == "false"
    assert "expectations" not in props
    assert ok.find("failure") is None and ok.find("error") is None
    failure = tight.find("failure")
    assert failure is not None
    assert failure.get("message") == "max_torque_ratio: peak torque ratio 0.13 > limit 0.001"
    assert {p.get("name"): p.get("value") for p in tight.iter("property")}["cached"] == "true"
    error = bad.find("error")
    assert error is not None
    assert error.get("message") == "suite/bad.yml:4:14: unknown action 'jump'"
    assert error.text is not None and "5:3" in error.text and "\x01" not in error.text
    assert skipped.find("skipped") is not None


def test_metric_properties_flatten_nested_values() -> None:
    assert metric_properties({"a": {"b": {"c": 1}}, "l": [1, None], "t": True}) == [
        ("a.b.c", "1"),
        ("l", "[1, null]"),
        ("t", "true"),
    ]


def test_write_junit_creates_folders(tmp_path: Path) -> None:
    path = tmp_path / "reports" / "report.xml"
    write_junit(_results(), path)
    assert path.read_text(encoding="utf-8").startswith("<?xml")
