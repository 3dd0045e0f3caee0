"""JSON encoding of log payloads and JSON Schema inference.

Payloads are mappings of numbers, strings, booleans, None, numpy arrays and scalars, lists,
tuples and nested mappings. They are written as strict JSON (RFC 8259): non-finite floats
(NaN, +-inf) become ``null`` because JSON has no literal for them and Foxglove's parser
rejects the ``NaN`` token Python would otherwise write.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Mapping, Sequence
from json.encoder import encode_basestring_ascii
from typing import Any

import numpy as np
import numpy.typing as npt

JsonSchema = dict[str, Any]


def _default(obj: object, decimals: int | None = None) -> Any:
    """Fallback of the fast encoder for the types `json` does not know (numpy, mappings)."""
    if isinstance(obj, np.ndarray):
        if decimals is not None and obj.dtype.kind == "f":
            return np.round(obj, decimals).tolist()
        return obj.tolist()
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating):
        return float(obj)
    if isinstance(obj, Mapping):
        return dict(obj)
    raise TypeError(f"cannot write a {type(obj).__name__} to a JSON log channel")


_STRICT_ENCODER = json.JSONEncoder(separators=(",", ":"), allow_nan=False)


def to_jsonable(value: Any, decimals: int | None = None) -> Any:
    """Return `value` as plain JSON types: numpy arrays become (nested) lists (float arrays
    rounded to `decimals` places if given), numpy scalars Python scalars, tuples lists, and
    non-finite floats None.

    Raises TypeError for anything else (objects, sets, bytes), and for non-string keys.
    """
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, float):  # includes np.float64
        return value if math.isfinite(value) else None
    if isinstance(value, int):
        return int(value)
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "biuf":
            raise TypeError(f"cannot write a numpy array of dtype {value.dtype} to a JSON log")
        if value.dtype.kind == "f":
            if decimals is not None:
                value = np.round(value, decimals)
            if not np.isfinite(value).all():
                return to_jsonable(value.tolist())
        return value.tolist()
    if isinstance(value, np.generic):
        return to_jsonable(value.item())
    if isinstance(value, Mapping):
        out = {}
        for key, item in value.items():
            if not isinstance(key, str):
                raise TypeError(f"JSON log keys must be str, got {key!r}")
            out[key] = to_jsonable(item, decimals)
        return out
    if isinstance(value, list | tuple):
        return [to_jsonable(item, decimals) for item in value]
    raise TypeError(f"cannot write a {type(value).__name__} to a JSON log channel")


class JsonEncoder:
    """Encodes payloads as compact strict JSON (UTF-8 bytes): ``encoder(payload)`` one,
    ``encoder.many(payloads)`` a batch (the same bytes, faster). See `make_json_encoder`."""

    def __init__(self, decimals: int | None = None) -> None:
        self.decimals = decimals
        self._encoder = json.JSONEncoder(
            separators=(",", ":"),
            allow_nan=True,
            default=_default
            if decimals is None
            else functools.partial(_default, decimals=decimals),
        )
        from locoplan.log.numfmt import MAX_DECIMALS, RoundedJson

        # The compiled path for float64 arrays, with `decimals` only (it rounds).
        self._rounded = (
            RoundedJson(decimals)
            if decimals is not None and 0 <= decimals <= MAX_DECIMALS
            else None
        )
        # an object's keys -> the texts around its values (see `_template`)
        self._templates: dict[tuple[Any, ...], list[bytes]] = {}

    def __call__(self, payload: Mapping[str, Any]) -> bytes:
        """One payload's bytes."""
        if self._rounded is None or not any(type(v) is np.ndarray for v in payload.values()):
            return self._plain(payload)  # no array: the C encoder alone is faster
        return self.many([payload])[0]

    def many(self, payloads: Sequence[Mapping[str, Any]]) -> list[bytes]:
        """``[self(p) for p in payloads]``, the same bytes, faster (`RunLogWriter` encodes its
        queue so).

        With `decimals`, the payloads are grouped by their keys (a topic's payloads share
        them) and each group is encoded column by column: one type check per column picks how
        its values are printed, and the float64 arrays of all the columns go to one compiled
        call (`locoplan.log.numfmt.RoundedJson.many`). That saves most of the per-value
        dispatch and about 1 us per array against encoding payload by payload (a fifth of the
        closed loop's JSON encoding time; even a payload of floats alone, which `__call__`
        leaves to the C encoder, costs a little less so).
        """
        if self._rounded is None:
            return [self._plain(p) for p in payloads]
        out: list[bytes] = [b""] * len(payloads)
        groups: dict[tuple[Any, ...], list[Mapping[str, Any]]] = {}
        where: dict[tuple[Any, ...], list[int]] = {}  # the group's payloads' places in `out`
        for i, payload in enumerate(payloads):
            keys = tuple(payload)
            group = groups.get(keys)
            if group is None:
                group = groups[keys] = []
                where[keys] = []
            group.append(payload)
            where[keys].append(i)
        arrays: list[npt.NDArray[np.float64]] = []  # every float64 array column, one list
        array_columns: list[tuple[list[bytes], int]] = []  # (its texts, its start in arrays)
        tables: list[tuple[list[bytes], list[int], list[list[bytes]]]] = []
        for keys, group in groups.items():
            template = self._template(keys)
            if template is None:  # a key that is no string: the C encoder's handling of those
                for i, payload in zip(where[keys], group, strict=True):
                    out[i] = self._plain(payload)
                continue
            columns = []
            for key in keys:
                column = [payload[key] for payload in group]
                texts = self._column_json(column)
                if texts is None:  # float64 arrays: printed below, all in one call
                    texts = [b""] * len(column)
                    array_columns.append((texts, len(arrays)))
                    arrays += column
                columns.append(texts)
            tables.append((template, where[keys], columns))
        printed = self._rounded.many(arrays)
        for texts, start in array_columns:
            for j in range(len(texts)):
                text = printed[start + j]
                # None: an array the compiled path does not take (see `locoplan.log.numfmt`)
                texts[j] = self._plain(arrays[start + j]) if text is None else text
        for template, places, columns in tables:
            rows = zip(*columns, strict=True) if columns else [()] * len(places)  # {}: no column
            for i, row in zip(places, rows, strict=True):
                parts = template.copy()
                parts[1::2] = row  # the values between the keys' texts
                out[i] = b"".join(parts)
        return out

    def _template(self, keys: tuple[Any, ...]) -> list[bytes] | None:
        """The texts around the values of an object with `keys`: ``{"a":``, a value's place,
        ``,"b":``, ..., ``}``; None for a key that is no string."""
        template = self._templates.get(keys)
        if template is None:
            if not all(isinstance(key, str) for key in keys):
                return None
            template = []
            for n, key in enumerate(keys):
                text = encode_basestring_ascii(key).encode() + b":"
                template += [(b"," if n else b"{") + text, b""]
            template.append(b"}" if keys else b"{}")
            self._templates[keys] = template
        return template

    def _column_json(self, column: list[Any]) -> list[bytes] | None:
        """The texts of one key's values in a group of payloads; None when they are all
        float64 arrays (for the compiled call). One type check for the column when its values
        have one type (what a topic's payloads hold), `_value_json` for each value otherwise."""
        kinds = set(map(type, column))
        if len(kinds) == 1:
            kind = kinds.pop()
            if kind is np.ndarray and all(v.dtype == np.float64 for v in column):
                return None
            if kind is bool:
                return [b"true" if v else b"false" for v in column]
            if kind is float:
                return [float.__repr__(v).encode() if math.isfinite(v) else b"null" for v in column]
            if kind is int:
                return [int.__repr__(v).encode() for v in column]
            if kind is str:
                return [encode_basestring_ascii(v).encode() for v in column]
        value_json = self._value_json
        return [value_json(v) for v in column]

    def _plain(self, payload: Any) -> bytes:
        """The C encoder's bytes; when it wrote NaN or Infinity (or a string merely holds the
        word), `to_jsonable` and the strict encoder's instead."""
        text = self._encoder.encode(payload)
        if "NaN" in text or "Infinity" in text:
            text = _STRICT_ENCODER.encode(to_jsonable(payload, self.decimals))
        return text.encode("utf-8")

    def _value_json(self, value: Any) -> bytes:
        """One top-level value; arrays of other dtypes and containers go through `_plain`."""
        kind = type(value)
        if kind is np.ndarray and value.dtype == np.float64:
            assert self._rounded is not None
            fast = self._rounded(value)
            if fast is not None:
                return fast
        elif kind is float or kind is np.float64:
            return float.__repr__(value).encode() if math.isfinite(value) else b"null"
        elif kind is bool or kind is np.bool_:
            return b"true" if value else b"false"
        elif kind is int:
            return int.__repr__(value).encode()
        elif kind is str:
            return encode_basestring_ascii(value).encode()
        elif value is None:
            return b"null"
        return self._plain(value)


def make_json_encoder(decimals: int | None = None) -> JsonEncoder:
    """An encoder of payloads as compact strict JSON (UTF-8 bytes): call it with one payload,
    or its `many` with a batch.

    With `decimals`, float numpy arrays are rounded to that many decimal places first (6 keeps
    micrometres, micronewtons and microradians and, since Python spends most of the encoding
    time printing 17 significant digits, saves about a quarter of the time and a fifth of the
    size of float-heavy payloads). Python float scalars are written in full.

    The fast path lets the C encoder do the work; only when its output holds a NaN or Infinity
    token (or a string that merely contains one) is the payload converted by `to_jsonable`
    and encoded again, strictly. With `decimals`, the top-level float64 arrays of a payload
    are printed by a compiled kernel (`locoplan.log.numfmt`, the same numbers, about ten times
    faster) and the other top-level values by a few type checks, so an MPC solution of 330
    numbers encodes in about 15 us instead of 120 us.
    """
    return JsonEncoder(decimals)


encode_json = make_json_encoder()


def infer_schema(payload: Mapping[str, Any], title: str) -> JsonSchema:
    """JSON Schema (draft 2020-12 subset) describing `payload`, named `title`.

    Numbers (int or float) map to ``number`` so a field that starts as 0 may later hold 0.5;
    numpy arrays map to nested ``array`` of ``number``/``boolean`` by dimension; lists take
    their item type from their first element (an empty list gets unconstrained items); None
    gets an unconstrained schema. Later payloads are not checked against it.
    """
    if not isinstance(payload, Mapping):
        raise TypeError(f"a JSON log payload must be a mapping, got {type(payload).__name__}")
    schema = _schema_of(payload)
    schema["title"] = title
    return schema


def _schema_of(value: Any) -> JsonSchema:
    if value is None:
        return {}
    if isinstance(value, bool | np.bool_):
        return {"type": "boolean"}
    if isinstance(value, int | float | np.integer | np.floating):
        return {"type": "number"}
    if isinstance(value, str):
        return {"type": "string"}
    if isinstance(value, np.ndarray):
        leaf: JsonSchema = {"type": "boolean"} if value.dtype.kind == "b" else {"type": "number"}
        for _ in range(value.ndim):
            leaf = {"type": "array", "items": leaf}
        return leaf
    if isinstance(value, Mapping):
        props = {}
        for key, item in value.items():
            if not isinstance(key, str):
                raise TypeError(f"JSON log keys must be str, got {key!r}")
            props[key] = _schema_of(item)
        return {"type": "object", "properties": props}
    if isinstance(value, list | tuple):
        return {"type": "array", "items": _schema_of(value[0]) if len(value) else {}}
    raise TypeError(f"cannot write a {type(value).__name__} to a JSON log channel")
