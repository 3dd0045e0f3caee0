"""Which pydantic model and field a document path (`loc`) points into, for messages that
list the allowed or required keys of a mapping or the length of a vector."""

from __future__ import annotations

import types
import typing
from collections.abc import Hashable
from typing import Any, Literal, get_args, get_origin

from pydantic import BaseModel
from pydantic.fields import FieldInfo

from locoplan.scenario.model import Scenario

Loc = tuple[Hashable, ...]


def _unwrap(tp: Any, action: str | None) -> Any:
    while True:
        origin = get_origin(tp)
        if origin is typing.Annotated:
            tp = get_args(tp)[0]
        elif origin in (typing.Union, types.UnionType):
            members = [a for a in get_args(tp) if a is not type(None)]
            if len(members) == 1:
                tp = members[0]
                continue
            for member in members:
                if _is_model(member) and _action_of(member) == action:
                    return member
            return None
        else:
            return tp


def _is_model(tp: Any) -> bool:
    return isinstance(tp, type) and issubclass(tp, BaseModel)


def _action_of(model: type[BaseModel]) -> str | None:
    info = model.model_fields.get("action")
    if info is None or get_origin(info.annotation) is not Literal:
        return None
    return str(get_args(info.annotation)[0])


def _resolve(loc: Loc, action: str | None) -> tuple[Any, FieldInfo | None]:
    """The type at `loc` (a model class, list type, ...) and the model field it belongs to."""
    tp: Any = Scenario
    info: FieldInfo | None = None
    for part in loc:
        tp = _unwrap(tp, action)
        if _is_model(tp):
            info = tp.model_fields.get(part) if isinstance(part, str) else None
            if info is None:
                return None, None
            tp = info.annotation
        elif get_origin(tp) is list and isinstance(part, int):
            tp, info = get_args(tp)[0], None
        elif get_origin(tp) is dict:
            tp, info = get_args(tp)[1], None
        else:
            return None, None
    return _unwrap(tp, action), info


def allowed_keys(parent: Loc, action: str | None) -> list[str]:
    model, _ = _resolve(parent, action)
    if not _is_model(model):
        return []
    names = list(model.model_fields)
    return sorted(names, key=lambda n: n != "action")  # stable: 'action' first


def required_keys(parent: Loc, action: str | None) -> list[str]:
    model, _ = _resolve(parent, action)
    if not _is_model(model):
        return []
    names = [n for n, f in model.model_fields.items() if f.is_required()]
    return sorted(names, key=lambda n: n != "action")


def fixed_length(loc: Loc, action: str | None) -> int | None:
    """N when the field at `loc` is a list of exactly N values (a vector), else None."""
    _, info = _resolve(loc, action)
    if info is None:
        return None
    low = high = None
    metadata = list(info.metadata)
    for arg in get_args(info.annotation):  # `Annotated[list, Field(...)] | None`
        metadata.extend(getattr(arg, "__metadata__", ()))
    for item in list(metadata):
        if isinstance(item, FieldInfo):  # `Field(min_length=...)` nested in an Annotated
            metadata.extend(item.metadata)
    for item in metadata:
        low = getattr(item, "min_length", low)
        high = getattr(item, "max_length", high)
    return low if low is not None and low == high else None
