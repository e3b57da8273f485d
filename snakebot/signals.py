"""The signals that ask snakebot to stop.

SIGINT (Ctrl-C), SIGTERM (a kill) and SIGHUP (the terminal or the SSH session went away) all mean
"stop": every command that drives servos ramps out and applies the stop policy on any of them.
"""

from __future__ import annotations

import signal

STOP_SIGNALS: tuple[signal.Signals, ...] = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)
"""Ctrl-C, a kill, a hang-up: each asks for a stop (SIGHUP does not exist on Windows)."""
