"""JUnit XML for a batch, in the shape CI systems read (GitHub test reporters, GitLab, Jenkins).

One `<testsuite name="locoplan">` with one `<testcase>` per script: `classname` its folder
(dotted), `name` its file name, `file` its path, `time` the worker's wall time (s). The run's
metrics are `<properties>` (nested values flattened with dots: `peak_torque.L_knee`); a failed
expectation is a `<failure message=...>` listing each one; a script that did not run to the
end (bad file, broken run, crashed or timed-out worker) is an `<error message=...>`, the
message naming the file, line and column for a bad file; `--fail-fast` leftovers are
`<skipped>`.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Iterator, Mapping, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from locoplan.batch.batch import BatchResult

# XML 1.0 forbids most control characters even as character references.
_INVALID_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ufffe\uffff]")
# Keys of the metrics object that are not numbers worth a property each.
_SKIPPED_KEYS = ("expectations",)


def _clean(text: str) -> str:
    return _INVALID_XML.sub("?", text)


def _flatten(prefix: str, value: Any) -> Iterator[tuple[str, str]]:
    if isinstance(value, Mapping):
        for k, v in value.items():
            yield from _flatten(f"{prefix}.{k}" if prefix else str(k), v)
    elif isinstance(value, list | tuple):
        yield prefix, "[" + ", ".join(_scalar(v) for v in value) + "]"
    else:
        yield prefix, _scalar(value)


def _scalar(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def metric_properties(metrics: Mapping[str, Any]) -> list[tuple[str, str]]:
    """The metrics as (name, value) pairs, nested mappings flattened with dots."""
    pairs: list[tuple[str, str]] = []
    for key, value in metrics.items():
        if key not in _SKIPPED_KEYS:
            pairs.extend(_flatten(str(key), value))
    return pairs


def junit_xml(results: Sequence[BatchResult], suite_name: str = "locoplan") -> str:
    """The JUnit XML document (UTF-8 text, with declaration) for `results`."""
    counts = {s: sum(r.outcome.status == s for r in results) for s in ("failed", "error")}
    skipped = sum(r.outcome.status == "skipped" for r in results)
    suite = ET.Element(
        "testsuite",
        {
            "name": suite_name,
            "tests": str(len(results)),
            "failures": str(counts["failed"]),
            "errors": str(counts["error"]),
            "skipped": str(skipped),
            "time": f"{sum(r.outcome.wall_time for r in results):.3f}",
            "timestamp": datetime.now(UTC).replace(microsecond=0).isoformat(),
        },
    )
    for result in results:
        case, outcome = result.case, result.outcome
        element = ET.SubElement(
            suite,
            "testcase",
            {
                "classname": case.classname,
                "name": case.path.name,
                "file": case.case_id,
                "time": f"{outcome.wall_time:.3f}",
            },
        )
        props = ET.SubElement(element, "properties")
        pairs: list[tuple[str, str]] = [("status", outcome.status)]
        pairs.append(("cached", "true" if outcome.cached else "false"))
        if outcome.metrics is not None:
            pairs += metric_properties(outcome.metrics)
        elif case.job is not None:
            pairs.append(("scenario", case.job.name))
        for name, value in pairs:
            ET.SubElement(props, "property", {"name": name, "value": _clean(value)})
        if outcome.status == "failed":
            failures = outcome.failures
            failure = ET.SubElement(
                element,
                "failure",
                {"message": _clean("; ".join(failures)), "type": "ExpectationFailed"},
            )
            failure.text = _clean("\n".join(failures))
        elif outcome.status == "error":
            error = ET.SubElement(
                element, "error", {"message": _clean(outcome.message), "type": "RunError"}
            )
            error.text = _clean(outcome.detail or outcome.message)
        elif outcome.status == "skipped":
            ET.SubElement(element, "skipped", {"message": _clean(outcome.message)})
    suites = ET.Element(
        "testsuites",
        {
            "name": suite_name,
            "tests": suite.get("tests", "0"),
            "failures": suite.get("failures", "0"),
            "errors": suite.get("errors", "0"),
            "skipped": suite.get("skipped", "0"),
            "time": suite.get("time", "0"),
        },
    )
    suites.append(suite)
    ET.indent(suites)
    return ET.tostring(suites, encoding="unicode", xml_declaration=True) + "\n"


def write_junit(results: Sequence[BatchResult], path: Path, suite_name: str = "locoplan") -> None:
    """Write `junit_xml(results)` to `path` (UTF-8); raises OSError when it cannot."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(junit_xml(results, suite_name), encoding="utf-8")
