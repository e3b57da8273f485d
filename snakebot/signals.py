"""The signals that ask snakebot to stop, and a clean Ctrl-C before the CLI's handlers are up.

SIGINT (Ctrl-C), SIGTERM (a kill) and SIGHUP (the terminal or the SSH session went away) all mean
"stop": every command that drives servos ramps out and applies the stop policy on any of them.
"""

from __future__ import annotations

import os
import signal
import sys
from types import FrameType

STOP_SIGNALS: tuple[signal.Signals, ...] = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)
"""Ctrl-C, a kill, a hang-up: each asks for a stop (SIGHUP does not exist on Windows)."""

START_UP_EXIT_CODE = 130


def interrupted_at_start_up(signum: int, frame: FrameType | None) -> None:
    """SIGINT while the ``snakebot`` command is still importing: say so and exit 130 at once.

    Nothing has touched a servo or a file yet, and a KeyboardInterrupt raised in the middle of
    an import (Python's own start-up code included) would print a traceback.
    """
    os.write(2, b"snakebot: interrupted\n")
    os._exit(START_UP_EXIT_CODE)


def started_as_command(argv: list[str], orig_argv: list[str]) -> bool:
    """Whether this process is the ``snakebot`` command: ``python -m snakebot`` (while Python
    is still finding the module, ``argv[0]`` is ``-m``) or the ``snakebot`` console script."""
    if argv[:1] == ["-m"]:
        for i, word in enumerate(orig_argv[1:], 1):
            if word == "-m":
                return orig_argv[i + 1:i + 2] == ["snakebot"]
            if word.startswith("-m"):
                return word[2:] == "snakebot"
        return False
    return bool(argv) and os.path.basename(argv[0]) in ("snakebot", "snakebot.exe")


def guard_start_up() -> None:
    """Install :func:`interrupted_at_start_up` for SIGINT if this process is the ``snakebot``
    command and Python's own handler is in place (the CLI's entry point replaces it)."""
    if not started_as_command(sys.argv, list(getattr(sys, "orig_argv", []))):
        return
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        signal.signal(signal.SIGINT, interrupted_at_start_up)
