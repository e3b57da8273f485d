"""Hold Ctrl-C and SIGTERM back while the last, short writes of a stop go out.

A signal handler that raises (Python's SIGINT handler, the CLI's SIGTERM one) can land between any
two bytecodes. During the final writes of a stop (torque off, watchdog disarmed) that would leave
the servos half-way, so those few milliseconds run with the handlers swapped for a recorder; a
signal that came in is re-delivered, as KeyboardInterrupt, once they are done.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType
from typing import Any

_SIGNALS = tuple(s for s in (signal.SIGINT, getattr(signal, "SIGTERM", None)) if s is not None)


@contextmanager
def deferred_interrupts() -> Iterator[list[int]]:
    """Run the block with raising SIGINT/SIGTERM handlers deferred; yields the signals caught.

    On exit, KeyboardInterrupt is raised if a deferred signal arrived (and no other exception is
    leaving the block). Outside the main thread, where handlers cannot be changed, nothing is
    deferred.
    """
    caught: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield caught
        return

    def record(signum: int, frame: FrameType | None) -> None:
        caught.append(signum)

    previous: dict[int, Any] = {}
    try:
        for signum in _SIGNALS:
            handler = signal.getsignal(signum)
            if callable(handler):  # handlers that would raise; SIG_DFL/SIG_IGN stay as they are
                previous[signum] = signal.signal(signum, record)
        yield caught
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
    if caught:
        raise KeyboardInterrupt
