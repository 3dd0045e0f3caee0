"""Compiled JSON text of rounded float arrays (numba, `cache=True`), for `locoplan.log.jsonenc`.

`rounded_json(a, decimals)` writes a float64 array as nested JSON lists of its values rounded
to `decimals` places, the values `np.round(a, decimals)` has (numpy multiplies by 10^decimals,
rounds half to even and divides by 10^decimals), and non-finite values as ``null``. Each number
is printed as the exact decimal k / 10^decimals with trailing zeros dropped (``0.000001``, not
``1e-06``); since parsing picks the double nearest to that decimal, and numpy's division gives
the double nearest to the same quotient, the text parses back to `np.round`'s double bit for bit.
That holds while |k| < 2^53 (|a| < 9e9 at 6 places); beyond, for an empty array or one of
more than 3 dimensions, `rounded_json` returns None and the caller formats the array the slow
way.

Python spends most of a JSON encoding printing floats one by one (about 0.35 us each); this
writes an MPC plan of 330 numbers in a few microseconds. `RoundedJson.many` writes a batch of
arrays in one call (a writer's queue holds hundreds of small ones, and each call from Python
costs about 1 us around the kernel).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
from numba import njit

MAX_DECIMALS = 15  # 10^15 < 2^53 leaves room for an integer part
_EXACT_LIMIT = float(2**53)  # integers up to here are exact doubles


@njit("int64(uint8[::1], int64, int64)", cache=True)
def _write_int(buf: npt.NDArray[np.uint8], pos: int, value: int) -> int:
    """Write `value` (>= 0) in decimal at `pos`; returns the position after it."""
    n = 1
    bound = 10
    while value >= bound and n < 19:
        n += 1
        bound *= 10
    end = pos + n
    k = end - 1
    while k >= pos:
        buf[k] = 48 + value % 10
        value //= 10
        k -= 1
    return end


# Explicit signatures: compiled (or loaded from the cache) at import, and an argument of
# another type is an error rather than a compilation in the middle of a run.
@njit(
    "int64(uint8[::1], int64, float64[::1], int64, int64, int64, int64, int64, int64, float64,"
    " int64)",
    cache=True,
)
def _write_array(
    buf: npt.NDArray[np.uint8],
    pos: int,
    flat: npt.NDArray[np.float64],
    start: int,
    n: int,
    ndim: int,
    size1: int,
    size2: int,
    decimals: int,
    scale: float,
    power: int,
) -> int:
    """Write the JSON text of ``flat[start:start + n]`` (C order) at `pos` as nested lists,
    `ndim` (1 to 3) deep, a depth-1 list holding `size1` numbers and a depth-2 list `size2`;
    returns the position after it, or -1 when a value is too large for the exact path (what
    was written from `pos` on is then garbage). `buf` needs `_bound(n, ndim, decimals)` bytes
    from `pos`."""
    for _ in range(ndim):
        buf[pos] = 91  # [
        pos += 1
    for i in range(n):
        if i > 0:
            c = 0  # lists closed before this number (and as many opened after the comma)
            if ndim >= 2 and i % size1 == 0:
                c += 1
            if ndim >= 3 and i % size2 == 0:
                c += 1
            for _ in range(c):
                buf[pos] = 93  # ]
                pos += 1
            buf[pos] = 44  # ,
            pos += 1
            for _ in range(c):
                buf[pos] = 91
                pos += 1
        v = flat[start + i]
        if not np.isfinite(v):
            buf[pos] = 110  # null
            buf[pos + 1] = 117
            buf[pos + 2] = 108
            buf[pos + 3] = 108
            pos += 4
            continue
        k = np.rint(v * scale)
        if abs(k) >= _EXACT_LIMIT:
            return -1
        if k < 0.0 or (k == 0.0 and np.signbit(k)):
            buf[pos] = 45  # -
            pos += 1
        m = int(abs(k))
        whole = m // power
        pos = _write_int(buf, pos, whole)
        buf[pos] = 46  # .
        pos += 1
        frac = m - whole * power
        if frac == 0:
            buf[pos] = 48
            pos += 1
            continue
        # All `decimals` digits (zero-padded), then the trailing zeros dropped.
        end = pos + decimals
        k_digit = end - 1
        while k_digit >= pos:
            buf[k_digit] = 48 + frac % 10
            frac //= 10
            k_digit -= 1
        while buf[end - 1] == 48:
            end -= 1
        pos = end
    for _ in range(ndim):
        buf[pos] = 93
        pos += 1
    return pos


@njit("int64(int64, int64, int64)", cache=True)
def _bound(n: int, ndim: int, decimals: int) -> int:
    """Bytes `_write_array` may need: per number sign, 16 integer digits, point, decimals and
    comma; brackets, 2 per list."""
    return n * (20 + decimals) + 2 * n * ndim + 2 * ndim + 8


@njit("uint8[::1](float64[::1], int64, int64, int64, int64, float64, int64)", cache=True)
def _format(
    flat: npt.NDArray[np.float64],
    ndim: int,
    size1: int,
    size2: int,
    decimals: int,
    scale: float,
    power: int,
) -> npt.NDArray[np.uint8]:
    """JSON text (ASCII bytes) of `flat` (C order) as nested lists (see `_write_array`); an
    empty array when a value is too large for the exact path."""
    n = flat.size
    buf = np.empty(_bound(n, ndim, decimals), dtype=np.uint8)
    pos = _write_array(buf, 0, flat, 0, n, ndim, size1, size2, decimals, scale, power)
    if pos < 0:
        return np.empty(0, dtype=np.uint8)
    return buf[:pos]


@njit(
    "Tuple((uint8[::1], int64[::1]))(float64[::1], int64[::1], int64, float64, int64)",
    cache=True,
)
def _format_many(
    flat: npt.NDArray[np.float64],
    spec: npt.NDArray[np.int64],
    decimals: int,
    scale: float,
    power: int,
) -> tuple[npt.NDArray[np.uint8], npt.NDArray[np.int64]]:
    """The JSON texts of many arrays in one call, one after the other in one buffer.

    `flat` holds the arrays' values one after the other (each in C order); `spec` four
    numbers per array: its size, ndim, size1 and size2 (see `_write_array`). Returns the
    buffer and, per array, where its text ends, or -1 when a value is too large for the exact
    path (that array then has no text: the next one starts where the previous one ended)."""
    k = spec.size // 4
    total = 0
    for j in range(k):
        total += _bound(spec[4 * j], spec[4 * j + 1], decimals)
    buf = np.empty(total, dtype=np.uint8)
    ends = np.empty(k, dtype=np.int64)
    pos = 0
    start = 0
    for j in range(k):
        n = spec[4 * j]
        end = _write_array(
            buf,
            pos,
            flat,
            start,
            n,
            spec[4 * j + 1],
            spec[4 * j + 2],
            spec[4 * j + 3],
            decimals,
            scale,
            power,
        )
        if end >= 0:
            pos = end
        ends[j] = end
        start += n
    return buf[:pos], ends


class RoundedJson:
    """`rounded_json` with `decimals` fixed (the per-call constants computed once)."""

    def __init__(self, decimals: int) -> None:
        if not 0 <= decimals <= MAX_DECIMALS:
            raise ValueError(f"decimals must be in [0, {MAX_DECIMALS}], got {decimals}")
        self.decimals = decimals
        self._scale = 10.0**decimals
        self._power = 10**decimals

    def __call__(self, a: npt.NDArray[np.float64]) -> bytes | None:
        """JSON text of float64 array `a`, or None (see `rounded_json`)."""
        ndim = a.ndim
        if a.size == 0 or not 1 <= ndim <= 3:
            return None
        shape = a.shape
        flat = a.reshape(-1)
        if not (flat.flags.c_contiguous and flat.flags.writeable):
            flat = flat.copy()
        size1 = shape[1] * shape[2] if ndim == 3 else shape[-1]
        out = _format(flat, ndim, size1, shape[-1], self.decimals, self._scale, self._power)
        return out.tobytes() if out.size else None

    def many(self, arrays: Sequence[npt.NDArray[np.float64]]) -> list[bytes | None]:
        """``[self(a) for a in arrays]``, the same bytes, in one compiled call.

        Each call of `__call__` costs about 1 us of Python and dispatch around the kernel
        (more than the kernel itself for the closed loop's arrays of 3 to 30 numbers); a
        writer's batch of queued payloads holds a few hundred arrays, so they are written
        together: their values joined into one buffer, one kernel call, then one slice each.
        """
        out: list[bytes | None] = [None] * len(arrays)
        used: list[npt.NDArray[np.float64]] = []
        where: list[int] = []  # index in `arrays` of each of `used`
        spec: list[int] = []  # per used array: size, ndim, size1, size2 (see `_format_many`)
        for i, a in enumerate(arrays):
            ndim = a.ndim
            if a.size == 0 or not 1 <= ndim <= 3:
                continue
            shape = a.shape
            spec += (a.size, ndim, shape[1] * shape[2] if ndim == 3 else shape[-1], shape[-1])
            used.append(a)
            where.append(i)
        if not used:
            return out
        flat = np.concatenate(used, axis=None)  # a new C-ordered float64 buffer
        buf, ends = _format_many(
            flat, np.array(spec, dtype=np.int64), self.decimals, self._scale, self._power
        )
        text = buf.tobytes()
        start = 0
        for i, end in zip(where, ends.tolist(), strict=True):
            if end >= 0:  # -1: a value too large for the exact path (None, as `__call__`)
                out[i] = text[start:end]
                start = end
        return out


def rounded_json(a: npt.NDArray[np.float64], decimals: int) -> bytes | None:
    """JSON text of float64 array `a` (1 to 3 dimensions, size > 0) rounded to `decimals`
    places (0 to `MAX_DECIMALS`), as ASCII bytes; None when the exact path does not apply
    (see the module docstring) or for other shapes."""
    if not 0 <= decimals <= MAX_DECIMALS:
        return None
    return RoundedJson(decimals)(a)
