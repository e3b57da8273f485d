"""Offscreen video of the twin with ``mujoco.Renderer``.

Headless Linux needs ``MUJOCO_GL=egl`` or ``osmesa`` before ``mujoco`` is imported;
snakebot.backends.offscreen_gl sets it when nothing else did (the twin package and the CLI call it
first).
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from types import TracebackType
from typing import Any

import mujoco

from snakebot.backends.twin.backend import Simulated
from snakebot.errors import MissingDependencyError, OutputError


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


_WRITER_FAILURES = (OSError, ValueError, RuntimeError)  # imageio / ffmpeg: format, pipe, disk


class VideoWriter:
    """RGB frames (height x width x 3, uint8) encoded to ``path`` at ``fps``; the one video
    writer of snakebot (``run --video``, ``rl eval --video``).

    A failed writer is an error, never a file that only looks written: imageio-ffmpeg does not
    check ffmpeg's exit status, so a disk that fills while ffmpeg writes the trailer ("Error
    writing trailer") would leave an unreadable file behind a normal close. :meth:`close`
    therefore has ffmpeg read the file back (counting packets, no decoding) and raises
    OutputError naming ``path`` unless it holds every frame written. Opening, appending and
    closing raise OutputError naming ``path`` too; MissingDependencyError without imageio.
    The file's folder is created.
    """

    def __init__(self, path: Path, fps: float) -> None:
        imageio = require_video_writer()
        self.path = path
        self.frames = 0
        self._closed = False
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            self._writer: Any = imageio.get_writer(str(path), fps=fps, macro_block_size=8)
        except _WRITER_FAILURES as exc:
            raise OutputError(path, f"cannot write the video: {exc}") from exc

    def append(self, frame: Any) -> None:
        """Encode one frame."""
        try:
            self._writer.append_data(frame)
        except _WRITER_FAILURES as exc:
            raise OutputError(self.path, f"cannot write the video: {_first_line(exc)}") from exc
        self.frames += 1

    def close(self) -> None:
        """Finish the file and check it reads back with every frame (once; later calls do
        nothing)."""
        if self._closed:
            return
        self._closed = True
        try:
            self._writer.close()
        except _WRITER_FAILURES as exc:
            raise OutputError(self.path, f"cannot finish the video: {_first_line(exc)}") from exc
        self._check()

    def _check(self) -> None:
        import imageio_ffmpeg

        try:
            found, _ = imageio_ffmpeg.count_frames_and_secs(str(self.path))
        except (OSError, RuntimeError) as exc:
            raise OutputError(
                self.path,
                f"the encoder did not finish the video (a full disk?): ffmpeg cannot "
                f"read it back ({_last_line(exc)}); {self.frames} frames were sent",
            ) from exc
        if found != self.frames:
            raise OutputError(
                self.path,
                f"the video holds {found} of the {self.frames} frames "
                "sent: the encoder did not finish it (a full disk?)",
            )

    def __enter__(self) -> VideoWriter:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc_type is None:
            self.close()
            return
        with contextlib.suppress(Exception):  # the error already raised is the one to report
            self.close()


def _first_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0]


def _last_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[-1].strip()


class VideoRecorder:
    """Renders every k-th control cycle from the tracking camera and encodes a video.

    ``rate_hz`` is the control rate; frames (``height`` x ``width`` RGB, uint8) are taken every
    ``round(rate_hz / fps)`` cycles, so the file plays in real time. The file's folder is created.
    Raises MissingDependencyError without imageio; OutputError naming the file when it cannot
    be written or does not read back whole (a :class:`VideoWriter`); ``mujoco.FatalError`` when
    no OpenGL context can be made (no offscreen platform: see snakebot.backends.offscreen_gl).
    ``frames`` counts the frames written.
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
        self.backend = backend
        self.path = path
        self.every = max(1, round(rate_hz / fps))
        self._writer = VideoWriter(path, rate_hz / self.every)
        try:
            self._renderer = mujoco.Renderer(backend.model, height, width)
        except BaseException:
            self._writer.__exit__(RuntimeError, None, None)
            raise

    @property
    def frames(self) -> int:
        """Frames written so far."""
        return self._writer.frames

    def __call__(self, cycle: int, gait_time_s: float) -> None:
        """Render a frame on every k-th cycle."""
        if cycle % self.every:
            return
        self._renderer.update_scene(self.backend.data, camera="track")
        self._writer.append(self._renderer.render())

    def __enter__(self) -> VideoRecorder:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        try:
            self._writer.__exit__(exc_type, exc, tb)
        finally:
            self._renderer.close()
