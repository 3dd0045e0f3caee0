"""`FrameRenderer`: one RGB frame of the scene from a `RenderSample`, headless.

Uses MuJoCo's own renderer (``mjv_updateScene`` / ``mjr_render``) on an offscreen buffer of
a software OpenGL context (`locoplan.render.gl`), on a private copy of the model and its own
MjData: the sample's qpos is set and only the kinematics are computed, so rendering never
touches the simulation's state. Per frame it adds a floor grid (1 m, so walking is visible
against the floor) and an overlay: time, active task(s), and the planned stance of each foot
as text and as two squares (green: stance, grey: swing).

Shadows, reflections and multisampling are off: with llvmpipe they cost 3x, 1.5x and 2x per
frame, and the directional light's shadow map showed acne on the 40 m floor.
"""

from __future__ import annotations

import copy
import math
import time

import mujoco
import numpy as np
import numpy.typing as npt

from locoplan.render.errors import RenderError
from locoplan.render.gl import open_gl_context
from locoplan.render.samples import RenderSample

UInt8Image = npt.NDArray[np.uint8]
FloatArray = npt.NDArray[np.float64]

GRID_SPACING = 1.0  # m between floor grid lines
GRID_HALF_EXTENT = 6  # lines each side of the look-at point
GRID_RGBA = (0.45, 0.45, 0.45, 1.0)
EXTRA_GEOMS = 4 * GRID_HALF_EXTENT + 8  # room in the mjvScene for the grid lines
STANCE_RGB = (0.15, 0.75, 0.25)
_ZERO3 = np.zeros(3)
_EYE9 = np.eye(3).ravel()
SWING_RGB = (0.35, 0.35, 0.35)


def stance_text(stance: tuple[bool, bool]) -> str:
    """``L+R`` (double support), ``L``, ``R`` (single support) or ``flight``."""
    names = [n for n, s in zip(("L", "R"), stance, strict=True) if s]
    return "+".join(names) if names else "flight"


class FrameRenderer:
    """Renders `width` x `height` frames of `model` (a compiled scene: robot + objects).

    `trunk_body` names the body the camera tracks. Holds a GL context: call `close` (or use
    as a context manager). RenderError when no OpenGL is available.
    """

    def __init__(self, model: mujoco.MjModel, trunk_body: str, width: int, height: int) -> None:
        if width <= 0 or height <= 0 or width % 2 or height % 2:
            raise ValueError(f"frame size must be positive and even, got {width}x{height}")
        self.width = width
        self.height = height
        m = copy.deepcopy(model)
        m.vis.global_.offwidth = max(width, int(m.vis.global_.offwidth))
        m.vis.global_.offheight = max(height, int(m.vis.global_.offheight))
        m.vis.quality.offsamples = 0
        self.model = m
        self.data = mujoco.MjData(m)
        self._trunk = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, trunk_body)
        if self._trunk < 0:
            raise RenderError("scene", f"the scene has no body {trunk_body!r} to follow")
        self.backend, self._gl = open_gl_context(width, height)
        self._context: mujoco.MjrContext | None = mujoco.MjrContext(
            m, mujoco.mjtFontScale.mjFONTSCALE_150
        )
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
        self._scene = mujoco.MjvScene(m, maxgeom=m.ngeom + EXTRA_GEOMS + 100)
        self._scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
        self._scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = False
        self._option = mujoco.MjvOption()
        self._perturb = mujoco.MjvPerturb()
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._pixels = np.empty((height, width, 3), dtype=np.uint8)
        self.render_times_s: list[float] = []

    def __enter__(self) -> FrameRenderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Free the GL resources. Idempotent."""
        if self._context is None:
            return
        self._context.free()
        self._context = None
        self._gl.free()

    def set_state(self, sample: RenderSample) -> tuple[FloatArray, FloatArray]:
        """Pose the private MjData at `sample`; returns the trunk position (3,) and
        quaternion (w, x, y, z). RenderError when the qpos does not fit the model."""
        if sample.qpos.shape != (self.model.nq,):
            raise RenderError(
                "scene",
                f"a sample at t={sample.t:.3f} s has {sample.qpos.shape[0]} qpos values but the "
                f"scene has nq={self.model.nq} (was the robot or the scenario changed?)",
            )
        self.data.qpos[:] = sample.qpos
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_camlight(self.model, self.data)
        return (
            np.asarray(self.data.xpos[self._trunk]).copy(),
            np.asarray(self.data.xquat[self._trunk]).copy(),
        )

    def render(
        self,
        sample: RenderSample,
        lookat: FloatArray,
        azimuth_deg: float,
        elevation_deg: float,
        distance: float,
    ) -> UInt8Image:
        """The frame (height, width, 3) uint8, top row first, of the state set by `set_state`
        for `sample`, seen from a free camera at `lookat` (3,) m, `azimuth_deg`,
        `elevation_deg`, `distance` (m). The returned array is reused by the next call."""
        if self._context is None:
            raise RenderError("opengl", "FrameRenderer is closed")
        t0 = time.perf_counter()
        m, con, scn, cam = self.model, self._context, self._scene, self._camera
        cam.lookat[:] = lookat
        cam.azimuth = azimuth_deg
        cam.elevation = elevation_deg
        cam.distance = distance
        mujoco.mjv_updateScene(
            m, self.data, self._option, self._perturb, cam, mujoco.mjtCatBit.mjCAT_ALL, scn
        )
        self._add_grid(scn, lookat)
        mujoco.mjr_render(self._rect, scn, con)
        self._overlay(sample)
        mujoco.mjr_readPixels(self._pixels, None, self._rect, con)
        frame = np.flipud(self._pixels)
        self.render_times_s.append(time.perf_counter() - t0)
        return frame

    def _add_grid(self, scn: mujoco.MjvScene, lookat: FloatArray) -> None:
        cx = math.floor(lookat[0] / GRID_SPACING) * GRID_SPACING
        cy = math.floor(lookat[1] / GRID_SPACING) * GRID_SPACING
        n, h = GRID_HALF_EXTENT, GRID_HALF_EXTENT * GRID_SPACING
        rgba = np.asarray(GRID_RGBA, dtype=np.float32)
        z = 0.001  # just above the floor plane, so the depth test keeps the lines
        for k in range(-n, n + 1):
            for a, b in (
                ((cx + k * GRID_SPACING, cy - h, z), (cx + k * GRID_SPACING, cy + h, z)),
                ((cx - h, cy + k * GRID_SPACING, z), (cx + h, cy + k * GRID_SPACING, z)),
            ):
                if scn.ngeom >= scn.maxgeom:
                    return
                geom = scn.geoms[scn.ngeom]
                mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_LINE, _ZERO3, _ZERO3, _EYE9, rgba)
                mujoco.mjv_connector(
                    geom, mujoco.mjtGeom.mjGEOM_LINE, 1.5, np.asarray(a), np.asarray(b)
                )
                scn.ngeom += 1

    def _overlay(self, sample: RenderSample) -> None:
        con = self._context
        assert con is not None
        mujoco.mjr_overlay(
            mujoco.mjtFont.mjFONT_NORMAL,
            mujoco.mjtGridPos.mjGRID_TOPLEFT,
            self._rect,
            "t\ntask\nstance",
            f"{sample.t:6.2f} s\n{sample.task}\n{stance_text(sample.stance)}",
            con,
        )
        size, gap, margin = 26, 8, 12
        for k, (label, on) in enumerate(zip(("L", "R"), sample.stance, strict=True)):
            x = margin + k * (size + gap)
            rgb = STANCE_RGB if on else SWING_RGB
            mujoco.mjr_rectangle(mujoco.MjrRect(x, margin, size, size), *rgb, 1.0)
            mujoco.mjr_text(
                mujoco.mjtFont.mjFONT_NORMAL,
                label,
                con,
                (x + size * 0.3) / self.width,
                (margin + size * 0.2) / self.height,
                1.0,
                1.0,
                1.0,
            )
