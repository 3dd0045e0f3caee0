"""An OpenGL context for MuJoCo's offscreen renderer on a machine with no display and no GPU.

MuJoCo's Python bindings pick their GL platform from ``MUJOCO_GL`` when ``mujoco`` is first
imported; a CLI or test process has usually imported it long before it renders. So the
context is created here from the platform module itself (``mujoco.egl`` or
``mujoco.osmesa``), which works whatever ``MUJOCO_GL`` said at import time.

Backends (``MUJOCO_GL`` chooses; default ``egl``):
- ``egl``: Mesa's EGL with the llvmpipe software rasteriser. Debian packages libegl1,
  libegl-mesa0 and libgl1-mesa-dri (the Python machine image has them). About 8.5 ms for a
  640x480 frame of the humanoid scene without shadows on this 2-core machine.
- ``osmesa``: Mesa's off-screen library, Debian package libosmesa6. Measured about 1.5x
  slower than EGL here. PyOpenGL binds one platform per process, so only one of the two
  can be used in a process: set ``MUJOCO_GL=osmesa`` before starting it.
"""

from __future__ import annotations

import importlib
import os
from typing import Protocol

from locoplan.render.errors import EGL_PACKAGES, OSMESA_PACKAGES, RenderError

BACKENDS = ("egl", "osmesa")
DEFAULT_BACKEND = "egl"


class GLContext(Protocol):
    """What MuJoCo's platform contexts offer (``mujoco.egl.GLContext`` and friends)."""

    def make_current(self) -> None: ...

    def free(self) -> None: ...


def gl_backend() -> str:
    """The backend ``MUJOCO_GL`` asks for (default egl). RenderError for another value."""
    name = os.environ.get("MUJOCO_GL", "").strip().lower() or DEFAULT_BACKEND
    if name not in BACKENDS:
        raise RenderError(
            "opengl",
            f"MUJOCO_GL={name!r} cannot render without a display; use one of {', '.join(BACKENDS)}",
        )
    return name


def packages_for(backend: str) -> tuple[str, ...]:
    """Debian packages the backend needs."""
    return OSMESA_PACKAGES if backend == "osmesa" else EGL_PACKAGES


def open_gl_context(width: int, height: int) -> tuple[str, GLContext]:
    """A current GL context with a `width` x `height` (pixels) default framebuffer, and the
    backend's name. RenderError naming the Debian packages to install when it fails."""
    backend = gl_backend()
    if backend == "osmesa":
        # PyOpenGL reads this when it is first imported; mujoco.egl sets it for EGL itself.
        os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")
    try:
        module = importlib.import_module(f"mujoco.{backend}")
        context: GLContext = module.GLContext(width, height)
        context.make_current()
    except Exception as exc:  # ImportError, OSError, RuntimeError, PyOpenGL's errors
        packages = " ".join(packages_for(backend))
        other = "osmesa" if backend == "egl" else "egl"
        raise RenderError(
            "opengl",
            f"no software OpenGL through {backend} ({type(exc).__name__}: {exc}). "
            f"Install the Debian packages {packages} (`make install` does as root), "
            f"or try MUJOCO_GL={other} with {' '.join(packages_for(other))}",
        ) from exc
    return backend, context


def check_gl() -> str:
    """Open and free a tiny context to find out whether rendering works here; returns the
    backend's name. RenderError (naming the packages to install) when it does not."""
    backend, context = open_gl_context(16, 16)
    context.free()
    return backend
