"""A rigid transform between two named frames, as logged on ``/tf``."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]
FloatsLike = Sequence[float] | npt.NDArray[np.floating]


@dataclass(frozen=True, slots=True)
class Transform:
    """Pose of `child_frame` expressed in `parent_frame`.

    `translation` (3,) is the child origin in the parent frame (m); `rotation` (4,) is the unit
    quaternion (x, y, z, w) rotating child-frame vectors into the parent frame -- pinocchio's
    order. MuJoCo's `xquat` is (w, x, y, z): reorder it (`q[[1, 2, 3, 0]]`) before passing it.
    Both are stored as tuples of floats (arrays are copied), so the value stays immutable.
    """

    parent_frame: str
    child_frame: str
    translation: FloatsLike
    rotation: FloatsLike

    def __post_init__(self) -> None:
        translation = _floats(self.translation, 3, "translation")
        rotation = _floats(self.rotation, 4, "rotation")
        if not self.child_frame or not self.parent_frame:
            raise ValueError("Transform needs non-empty parent_frame and child_frame")
        if self.child_frame == self.parent_frame:
            raise ValueError(f"Transform from {self.parent_frame!r} to itself")
        object.__setattr__(self, "translation", translation)
        object.__setattr__(self, "rotation", rotation)


def _floats(values: FloatsLike, n: int, what: str) -> tuple[float, ...]:
    """`values` as a tuple of `n` Python floats; ValueError on another length."""
    if isinstance(values, np.ndarray) and values.ndim == 1 and values.dtype.kind == "f":
        out = tuple(values.tolist())  # 5x faster than float() on each numpy scalar
    else:
        out = tuple(map(float, values))
    if len(out) != n:
        raise ValueError(f"Transform {what} needs {n} values, got {len(out)}")
    return out
