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
from collections.abc import Callable, Mapping
from json.encoder import encode_basestring_ascii
from typing import Any

import numpy as np

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


def make_json_encoder(decimals: int | None = None) -> Callable[[Mapping[str, Any]], bytes]:
    """A function encoding one payload as compact strict JSON (UTF-8 bytes).

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
    encoder = json.JSONEncoder(
        separators=(",", ":"),
        allow_nan=True,
        default=_default if decimals is None else functools.partial(_default, decimals=decimals),
    )

    def encode(payload: Mapping[str, Any]) -> bytes:
        text = encoder.encode(payload)
        if "NaN" in text or "Infinity" in text:
            text = _STRICT_ENCODER.encode(to_jsonable(payload, decimals))
        return text.encode("utf-8")

    if decimals is None:
        return encode

    from locoplan.log.numfmt import MAX_DECIMALS, RoundedJson

    if not 0 <= decimals <= MAX_DECIMALS:
        return encode
    rounded_json = RoundedJson(decimals)
    keys: dict[str, bytes] = {}

    def value_json(value: Any) -> bytes:
        """One top-level value; arrays of other dtypes and containers go through `encode`'s
        path (the C encoder, then the strict re-encoding when non-finite)."""
        kind = type(value)
        if kind is np.ndarray and value.dtype == np.float64:
            fast = rounded_json(value)
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
        text = encoder.encode(value)
        if "NaN" in text or "Infinity" in text:
            text = _STRICT_ENCODER.encode(to_jsonable(value, decimals))
        return text.encode("utf-8")

    def encode_fast(payload: Mapping[str, Any]) -> bytes:
        if not any(type(value) is np.ndarray for value in payload.values()):
            return encode(payload)  # no array: the C encoder alone is faster
        parts = []
        for key, value in payload.items():
            prefix = keys.get(key)
            if prefix is None:
                if not isinstance(key, str):
                    return encode(payload)  # the C encoder's handling of other keys
                prefix = keys[key] = encode_basestring_ascii(key).encode() + b":"
            parts.append(prefix + value_json(value))
        return b"{" + b",".join(parts) + b"}"

    return encode_fast


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
