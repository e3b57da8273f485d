"""Hold the stop signals (``snakebot.signals.STOP_SIGNALS``) back while a stop goes out.

A signal handler that raises (Python's SIGINT handler, the CLI's SIGTERM/SIGHUP one) can land
between any two bytecodes, inside the SDK's packet code included. During a stop that would leave
the servos half-way (a ramp cut short before the stop policy went out), so the whole stop runs
with those handlers swapped for a recorder: the stop asks how many came (``count``) and shortens
itself, and the signals are re-delivered to the handlers they were meant for (raising their
KeyboardInterrupt or SystemExit) once the final writes are out.
"""

from __future__ import annotations

import signal
import threading
from types import FrameType, TracebackType
from typing import Any

from snakebot.signals import STOP_SIGNALS


class DeferredInterrupts:
    """Context manager: raising handlers of :data:`STOP_SIGNALS` record instead, until exit.

    ``count`` is how many interruptions came in: signals recorded, plus KeyboardInterrupts the
    code inside handed to :meth:`note` (one raised by hand, or by a handler that ran before the
    recorder was in place). On a clean exit the first one is raised: a noted exception as it
    was, a recorded signal by calling the handler it was meant for. Outside the main thread,
    where handlers cannot be changed, nothing is swapped (``note`` still counts).
    """

    def __init__(self) -> None:
        self.caught: list[int] = []
        """The signal numbers recorded, in order."""
        self._raised: list[BaseException] = []
        self._previous: dict[int, Any] = {}

    @property
    def count(self) -> int:
        """Interruptions so far (signals recorded and exceptions noted)."""
        return len(self.caught) + len(self._raised)

    def note(self, exc: BaseException) -> None:
        """Count ``exc`` (a KeyboardInterrupt caught inside) and raise it at exit."""
        self._raised.append(exc)

    def _record(self, signum: int, frame: FrameType | None) -> None:
        self.caught.append(signum)

    def __enter__(self) -> DeferredInterrupts:
        if threading.current_thread() is not threading.main_thread():
            return self
        for signum in STOP_SIGNALS:
            while signum not in self._previous:
                try:
                    handler = signal.getsignal(signum)
                    if not callable(handler):  # SIG_DFL/SIG_IGN do not raise; they stay
                        break
                    # signal.signal runs pending handlers first and swaps only if none raised
                    self._previous[signum] = signal.signal(signum, self._record)
                except (KeyboardInterrupt, SystemExit) as exc:  # the old handler ran first
                    self._raised.append(exc)
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        previous = dict(self._previous)
        while self._previous:
            signum, handler = next(iter(self._previous.items()))
            try:
                signal.signal(signum, handler)
                del self._previous[signum]
            except (KeyboardInterrupt, SystemExit) as late:  # a handler put back already ran
                self._raised.append(late)
        if exc is not None:
            return
        if self._raised:
            raise self._raised[0]
        if self.caught:
            handler = previous.get(self.caught[0])
            if callable(handler):
                handler(self.caught[0], None)
            else:
                raise KeyboardInterrupt


def deferred_interrupts() -> DeferredInterrupts:
    """A :class:`DeferredInterrupts` (``with deferred_interrupts() as signals: ...``)."""
    return DeferredInterrupts()
