"""Sorted, disjoint half-open time intervals [t0, t1) with scalar and vectorised membership."""

from __future__ import annotations

import bisect
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]


@dataclass(frozen=True, slots=True, eq=False)
class Intervals:
    """Disjoint intervals [start[i], end[i]) sorted by start (s); end may be inf."""

    start: FloatArray
    end: FloatArray
    _start_list: list[float]

    def contains(self, t: float) -> bool:
        """Whether t lies in one of the intervals."""
        i = bisect.bisect_right(self._start_list, t) - 1
        return i >= 0 and t < self.end[i]

    def index(self, t: float) -> int:
        """Index of the interval containing t, or -1."""
        i = bisect.bisect_right(self._start_list, t) - 1
        return i if i >= 0 and t < self.end[i] else -1

    def contains_array(self, times: npt.ArrayLike) -> BoolArray:
        """Membership of every time of `times` (n,) -> (n,) bool."""
        times = np.asarray(times, dtype=float)
        if self.start.size == 0:
            return np.zeros(times.shape, dtype=bool)
        i = np.searchsorted(self.start, times, side="right") - 1
        return (i >= 0) & (times < self.end[np.maximum(i, 0)])

    def as_tuples(self) -> tuple[tuple[float, float], ...]:
        """The intervals as ((t0, t1), ...)."""
        return tuple(zip(self.start.tolist(), self.end.tolist(), strict=True))

    def __len__(self) -> int:
        return len(self._start_list)


def merge_intervals(pairs: list[tuple[float, float]]) -> Intervals:
    """Union of possibly overlapping or touching intervals, as disjoint sorted `Intervals`."""
    merged: list[list[float]] = []
    for a, b in sorted(p for p in pairs if p[1] > p[0]):
        if merged and a <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    return Intervals(
        np.array([m[0] for m in merged], dtype=float),
        np.array([m[1] for m in merged], dtype=float),
        [m[0] for m in merged],
    )
