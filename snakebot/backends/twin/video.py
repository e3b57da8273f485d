"""Offscreen video of the twin with ``mujoco.Renderer``.

Headless Linux needs ``MUJOCO_GL=egl`` or ``osmesa`` before ``mujoco`` is imported;
snakebot.backends.offscreen_gl sets it when nothing else did (the twin package and the CLI call it
first).
"""

from __future__ import annotations

from pathlib import Path
from types import TracebackType
from typing import Any

import mujoco

from snakebot.backends.twin.backend import Simulated
from snakebot.errors import MissingDependencyError


def require_video_writer() -> Any:
    """The ``imageio.v2`` module; MissingDependencyError with the install command without it.
    Cheap to call before any output opens."""
    try:
        import imageio.v2 as imageio
    except ImportError as exc:
        raise MissingDependencyError(
            "video output needs imageio and its ffmpeg plugin: pip install 'snakebot[video]'"
        ) from exc
    return imageio


class VideoRecorder:
    """Renders every k-th control cycle from the tracking camera and encodes a video.

    ``rate_hz`` is the control rate; frames (``height`` x ``width`` RGB, uint8) are taken every
    ``round(rate_hz / fps)`` cycles, so the file plays in real time. The file's folder is created.
    Raises MissingDependencyError without imageio; imageio/ffmpeg's OSError or ValueError for a
    file it cannot write; ``mujoco.FatalError`` when no OpenGL context can be made (no offscreen
    platform: see snakebot.backends.offscreen_gl). ``frames`` counts the frames written.
    """

    def __init__(
        self,
        backend: Simulated,
        path: Path,
        rate_hz: float,
        *,
        fps: int = 25,
        width: int = 640,
        height: int = 480,
    ) -> None:
        imageio = require_video_writer()
        self.backend = backend
        self.path = path
        self.every = max(1, round(rate_hz / fps))
        self.frames = 0
        path.parent.mkdir(parents=True, exist_ok=True)
        self._writer: Any = imageio.get_writer(
            str(path), fps=rate_hz / self.every, macro_block_size=8
        )
        self._renderer = mujoco.Renderer(backend.model, height, width)

    def __call__(self, cycle: int, gait_time_s: float) -> None:
        """Render a frame on every k-th cycle."""
        if cycle % self.every:
            return
        self._renderer.update_scene(self.backend.data, camera="track")
        self._writer.append_data(self._renderer.render())
        self.frames += 1

    def __enter__(self) -> VideoRecorder:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._writer.close()
        self._renderer.close()
