"""Pick MuJoCo's OpenGL platform for offscreen rendering before ``mujoco`` is first imported.

MuJoCo reads ``MUJOCO_GL`` once, when ``import mujoco`` runs; on Linux without a display its
default (GLFW) cannot render, so ``--video`` and ``mujoco.Renderer`` fail. This module imports
nothing heavy, so the CLI and the twin package call :func:`choose_offscreen_gl` first.
"""

from __future__ import annotations

import ctypes.util
import os
import sys
from collections.abc import Callable, MutableMapping

__all__ = ["choose_offscreen_gl"]

# In order of preference: EGL renders on a GPU or Mesa's llvmpipe; OSMesa is pure software.
_PLATFORMS = (("egl", "EGL"), ("osmesa", "OSMesa"))


def choose_offscreen_gl(
    environ: MutableMapping[str, str] | None = None,
    *,
    platform: str = sys.platform,
    find_library: Callable[[str], str | None] = ctypes.util.find_library,
) -> str | None:
    """Set ``MUJOCO_GL`` to ``egl`` (else ``osmesa``) when nothing chose a platform yet.

    Only on Linux, only when neither ``DISPLAY`` nor ``WAYLAND_DISPLAY`` is set (with a display
    GLFW works and the viewer needs it) and ``MUJOCO_GL`` is unset or empty (the user's choice
    wins), and only a platform whose library is installed (``find_library``: ``EGL``, then
    ``OSMesa``). Returns the value set, or None when it changed nothing. Has no effect once
    ``mujoco`` was imported, which is why callers run it first. Raises nothing.
    """
    env = os.environ if environ is None else environ
    if not platform.startswith("linux") or env.get("MUJOCO_GL"):
        return None
    if env.get("DISPLAY") or env.get("WAYLAND_DISPLAY"):
        return None
    for value, library in _PLATFORMS:
        if find_library(library):
            env["MUJOCO_GL"] = value
            # mujoco.egl / mujoco.osmesa set this too, but only if PyOpenGL is not imported yet.
            env.setdefault("PYOPENGL_PLATFORM", value)
            return value
    return None
