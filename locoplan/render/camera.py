"""The video camera: a free camera that follows the trunk from a fixed diagonal, smoothly.

The view direction is fixed in the world (set from the trunk's yaw in the first frame, looking
from behind-left of the robot), so turns are seen as turns; only the point looked at moves,
a first-order low-pass of the trunk position sampled once per frame. The filter runs per
frame, not per physics step, so the same frames give the same camera whether they come
live from a run or from its log.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class CameraSettings:
    """`distance` (m) from the point looked at; `elevation_deg` (negative looks down);
    `azimuth_offset_deg` added to the first trunk yaw to get the view direction (-45: looking
    forward-right, from behind-left); `time_constant` (s) of the tracking low-pass;
    `height_offset` (m) of the point looked at relative to the trunk origin."""

    distance: float = 2.6
    elevation_deg: float = -22.0
    azimuth_offset_deg: float = -45.0
    time_constant: float = 0.4
    height_offset: float = -0.15

    def __post_init__(self) -> None:
        if not self.distance > 0.0:
            raise ValueError(f"camera distance must be positive, got {self.distance}")
        if not self.time_constant >= 0.0:
            raise ValueError(f"time_constant must be >= 0, got {self.time_constant}")


def yaw_of_quat_wxyz(q: npt.ArrayLike) -> float:
    """Yaw (rad) of a unit quaternion (w, x, y, z)."""
    w, x, y, z = (float(v) for v in np.asarray(q, dtype=float)[:4])
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


class TrackingCamera:
    """Smoothed look-at point, updated once per frame of a video at `fps`."""

    def __init__(self, settings: CameraSettings, fps: int) -> None:
        self.settings = settings
        tau = settings.time_constant
        # Exact discretisation of a first-order low-pass at the frame period.
        self._alpha = 1.0 if tau == 0.0 else 1.0 - math.exp(-1.0 / (fps * tau))
        self.lookat: FloatArray | None = None
        self.azimuth_deg = 0.0

    def update(self, trunk_position: npt.ArrayLike, trunk_quat_wxyz: npt.ArrayLike) -> FloatArray:
        """Advance one frame towards the trunk at `trunk_position` (3,) m; returns the
        look-at point (3,). The first call also fixes the azimuth from the trunk's yaw."""
        target = np.asarray(trunk_position, dtype=float).copy()
        target[2] += self.settings.height_offset
        if self.lookat is None:
            self.lookat = target
            yaw = math.degrees(yaw_of_quat_wxyz(trunk_quat_wxyz))
            self.azimuth_deg = yaw + self.settings.azimuth_offset_deg
        else:
            self.lookat = self.lookat + self._alpha * (target - self.lookat)
        return self.lookat.copy()
