"""Errors of the renderer; they carry data, the CLI maps them to exit codes."""

from __future__ import annotations

from pathlib import Path

from locoplan.exceptions import LocoplanError

# Debian packages that give MuJoCo a software OpenGL without a display or a GPU.
EGL_PACKAGES = ("libegl1", "libegl-mesa0", "libgl1-mesa-dri")
OSMESA_PACKAGES = ("libosmesa6",)


class RenderError(LocoplanError):
    """Rendering or encoding a video failed: no OpenGL, no encoder, or unusable input.

    `what` names the stage ("opengl", "encoder", "log", "scene"), `detail` says why, and `path`
    is the file concerned when there is one.
    """

    def __init__(self, what: str, detail: str, path: Path | None = None) -> None:
        self.what = what
        self.detail = detail
        self.path = path
        where = f"{path}: " if path is not None else ""
        super().__init__(f"{where}{detail}")
