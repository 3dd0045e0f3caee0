"""Sweep plots (locoplan/report/sweep_plot.py): PNGs for one, two and three keys."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from locoplan.report.sweep_plot import plot_sweep


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = struct.unpack(">II", data[16:24])
    return width, height


def _row(**values: object) -> dict[str, object]:
    return {"fell": False, "passed": True, "peak_torque_ratio": 0.5, **values}


def test_one_key_line_with_marked_points(tmp_path: Path) -> None:
    rows = [
        _row(m=0, peak_torque_ratio=0.4),
        _row(m=4, peak_torque_ratio=0.9, passed=False),
        _row(m=6, peak_torque_ratio=1.0, completed=False),
        _row(m=8, peak_torque_ratio=1.3, fell=True, passed=False),
        _row(m=12, peak_torque_ratio=None, fell=None, passed=None),
    ]
    path = tmp_path / "line.png"
    plot_sweep(rows, ["m"], "peak_torque_ratio", path)
    assert _png_size(path) == (880, 550)  # 8 x 5 in at 110 dpi


def test_two_keys_heat_map(tmp_path: Path) -> None:
    rows = [
        _row(a=a, b=b, completion_time=a + b, fell=(a == 2 and b == 0.4))
        for a in (1, 2)
        for b in (0.3, 0.4)
    ]
    path = tmp_path / "heat.png"
    plot_sweep(rows, ["a", "b"], "completion_time", path)
    assert _png_size(path) == (880, 550)


def test_more_keys_and_text_values_use_the_point_index(tmp_path: Path) -> None:
    rows = [_row(a=1, b="left", c=True), _row(a=2, b="right", c=False)]
    path = tmp_path / "many.png"
    plot_sweep(rows, ["a", "b", "c"], "passed", path)
    assert _png_size(path) == (880, 550)


def test_errors() -> None:
    with pytest.raises(ValueError, match="at least one key"):
        plot_sweep([], [], "fell", "x.png")
