"""Signals as stop requests: the drive loop asks every cycle instead of being interrupted.

The same stop signals as every other command (``snakebot.signals.STOP_SIGNALS``), asked for
instead of raised: an exception raised inside a bus transaction can leave the SDK's port flagged
busy; a flag read at the top of the next cycle cannot. SIGINT and SIGTERM ask for a stop (rest
pose, then the stop policy); SIGHUP (the terminal closed) reports the input lost. A second SIGINT
while stopping raises KeyboardInterrupt, for a loop that no longer answers; the backend still
closes safely (its stop defers every stop signal until the stop policy is out).
"""

from __future__ import annotations

import signal
from types import FrameType, TracebackType
from typing import Any

from snakebot.signals import STOP_SIGNALS

_REASONS = {
    sig: "input lost: the terminal hung up (SIGHUP)"
    if sig.name == "SIGHUP"
    else f"interrupted ({sig.name})"
    for sig in STOP_SIGNALS
}


class StopSignals:
    """Context manager: while inside, the signals above set ``reason`` instead of killing."""

    def __init__(self) -> None:
        self.reason: str | None = None
        self._previous: dict[signal.Signals, Any] = {}

    def __call__(self) -> str | None:
        """The stop reason, once a signal came (the drive loop's stop check)."""
        return self.reason

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self.reason is not None and signum == signal.SIGINT:
            raise KeyboardInterrupt
        if self.reason is None:
            self.reason = _REASONS[signal.Signals(signum)]

    def __enter__(self) -> StopSignals:
        try:
            for sig in _REASONS:
                self._previous[sig] = signal.signal(sig, self._handle)
        except ValueError:  # not the main thread: leave the defaults
            self._restore()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self._restore()

    def _restore(self) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous.clear()
