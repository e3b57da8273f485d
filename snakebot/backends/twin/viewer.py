"""MuJoCo's passive viewer on the twin, synced once per control cycle."""

from __future__ import annotations

import os
from types import TracebackType
from typing import Any

from snakebot.backends.twin.backend import Simulated
from snakebot.errors import BackendError


def check_display() -> None:
    """BackendError unless a window can open (a display on Linux/BSD; always on macOS and
    Windows). Cheap: callers run it before opening any output file."""
    if (
        os.name == "posix"
        and not os.environ.get("DISPLAY")
        and not os.environ.get("WAYLAND_DISPLAY")
        and os.uname().sysname != "Darwin"
    ):
        raise BackendError(
            "the live viewer needs a display (DISPLAY is not set); record a video file "
            "instead, which renders offscreen"
        )


class PassiveViewer:
    """Opens ``mujoco.viewer.launch_passive``; closing the window stops nothing but the view."""

    def __init__(self, backend: Simulated) -> None:
        check_display()
        import mujoco.viewer

        self._handle: Any = mujoco.viewer.launch_passive(backend.model, backend.data)

    def __call__(self, cycle: int, gait_time_s: float) -> None:
        """Show the current state."""
        if self._handle.is_running():
            self._handle.sync()

    def __enter__(self) -> PassiveViewer:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._handle.close()
