"""Hold the stop signals (``snakebot.signals.STOP_SIGNALS``) back to safe points.

Two users: a servo chain, from the moment it may put torque on until its stop policy is out
(below), and ``run_gait``, for the whole run on any backend, so that a stop reaches the loop
between cycles and every observer of a cycle's record (the CSV log, the MCAP file) sees the same
cycles: a KeyboardInterrupt between two sinks once left the MCAP file a joint state short.

A signal handler that raises (Python's SIGINT handler, the CLI's SIGTERM/SIGHUP one) can land
between any two bytecodes: inside the SDK's packet code, or at the entry of the ``__exit__`` that
was about to stop the servos, leaving them energised with the Bus Watchdog tripping. So from the
moment a connecting backend may put torque on until its stop policy is out, those handlers are
swapped for a recorder. The backend hands the recorded signals to the handlers they were meant
for at safe points (the start of its cycle calls, see :meth:`DeferredInterrupts.deliver`), so a
loop still gets its KeyboardInterrupt within a cycle; the stop asks how many are waiting
(``count``) and shortens itself; the first one still waiting is delivered after the policy.
A loop stuck in its own code is not left deaf: a signal that comes while an earlier one has
waited ``UNANSWERED_S`` for a safe point is delivered at once (never during a stop).

One recorder serves every armed :class:`DeferredInterrupts` (several backends in one process):
the handlers are swapped when the first arms and put back when the last lets go.
"""

from __future__ import annotations

import signal
import threading
import time
from types import FrameType, TracebackType
from typing import Any

from snakebot.signals import STOP_SIGNALS

UNANSWERED_S = 2.0
"""A stop signal that comes while an earlier one has waited this long for a safe point (a loop
that stopped calling the backend: stuck in its own code) is delivered at once, outside a stop."""


class _Recorder:
    """The process's one recorder: the handlers it replaced and the signals not yet delivered."""

    def __init__(self) -> None:
        self.holders: list[DeferredInterrupts] = []
        self.previous: dict[int, Any] = {}
        self.pending: list[int] = []
        self.waiting_since: float | None = None

    def record(self, signum: int, frame: FrameType | None) -> None:
        if not self.holders:  # put back by code that saved it while armed: be what it replaced
            deliver_to(self.previous.get(signum), signum)
            return
        for holder in self.holders:
            holder.caught.append(signum)
        now = time.monotonic()
        if self.waiting_since is None or not self.pending:
            self.waiting_since = now
        elif now - self.waiting_since >= UNANSWERED_S and not any(
            holder.stopping for holder in self.holders
        ):
            deliver_to(self.previous.get(signum), signum)  # nobody asks: a stuck loop
            return
        self.pending.append(signum)

    def take(self) -> int | None:
        """The first waiting signal, now delivered; the next one waits from now."""
        if not self.pending:
            return None
        self.waiting_since = time.monotonic()
        return self.pending.pop(0)

    def arm(self, holder: DeferredInterrupts) -> None:
        self.holders.append(holder)
        if len(self.holders) > 1:
            return
        before, self.previous = self.previous, {}
        for signum in STOP_SIGNALS:
            while signum not in self.previous:
                try:
                    handler = signal.getsignal(signum)
                    if handler == self.record and signum in before:  # left by code that saved it
                        self.previous[signum] = before[signum]
                    if not callable(handler) or handler == self.record:
                        break  # SIG_DFL/SIG_IGN do not raise; they stay
                    # signal.signal runs pending handlers first and swaps only if none raised
                    self.previous[signum] = signal.signal(signum, self.record)
                except (KeyboardInterrupt, SystemExit) as exc:  # the old handler ran first
                    holder.note(exc)

    def release(self, holder: DeferredInterrupts, take: bool) -> int | None:
        """``holder`` lets go; the first waiting signal if ``take``. The last one out puts the
        handlers back (signals during that are still recorded) and drops the rest."""
        if len(self.holders) == 1:
            for signum, handler in self.previous.items():
                if signal.getsignal(signum) == self.record:
                    signal.signal(signum, handler)  # the recorder records, so this cannot raise
        self.holders.remove(holder)
        first = self.take() if take else None
        if not self.holders:
            self.pending.clear()
        return first


_RECORDER = _Recorder()


def deliver_to(handler: Any, signum: int) -> None:
    """Call the Python ``handler`` a recorded ``signum`` was meant for (KeyboardInterrupt if it
    is not one)."""
    if callable(handler):
        handler(signum, None)
    else:
        raise KeyboardInterrupt


class DeferredInterrupts:
    """Raising handlers of :data:`STOP_SIGNALS` record instead, from :meth:`arm` (or entering the
    context manager) until the context manager exits.

    ``count`` is how many interruptions are waiting: signals recorded and not yet delivered, plus
    KeyboardInterrupts handed to :meth:`note` (one raised by hand, or by a handler that ran
    before the recorder was in place). On a clean exit the first one is raised: a noted
    exception as it was, a recorded signal by calling the handler it was meant for. Outside the
    main thread, where handlers cannot be changed, nothing is swapped (``note`` still counts).
    """

    def __init__(self) -> None:
        self.caught: list[int] = []
        """The signal numbers recorded while armed, in order (delivered ones included)."""
        self._raised: list[BaseException] = []
        self._armed = False
        self.stopping = False
        """Inside the context manager (a stop): signals are only ever counted there."""

    @property
    def count(self) -> int:
        """Interruptions waiting (signals recorded and not delivered, exceptions noted)."""
        return (len(_RECORDER.pending) if self._armed else 0) + len(self._raised)

    def note(self, exc: BaseException) -> None:
        """Count ``exc`` (a KeyboardInterrupt caught inside) and raise it at exit."""
        self._raised.append(exc)

    def arm(self) -> None:
        """Start recording (again a no-op once armed, and outside the main thread)."""
        if self._armed or threading.current_thread() is not threading.main_thread():
            return
        self._armed = True
        _RECORDER.arm(self)

    def deliver(self) -> None:
        """A safe point: raise the first noted exception, or hand the first waiting signal to
        its handler (which raises its KeyboardInterrupt or SystemExit, or sets its flag)."""
        if self._raised:
            raise self._raised.pop(0)
        if self._armed and (signum := _RECORDER.take()) is not None:
            deliver_to(_RECORDER.previous.get(signum), signum)

    def release(self) -> None:
        """Stop recording, outside a stop: the first interruption still waiting (a noted one
        first) is raised now, as at a clean exit of the context manager; the others are kept
        for the holders still armed, or dropped with the last one. Call it only when no
        exception is leaving (``abandon`` then)."""
        first = _RECORDER.release(self, take=not self._raised) if self._armed else None
        self._armed = False
        if self._raised:
            raise self._raised.pop(0)
        if first is not None:
            deliver_to(_RECORDER.previous.get(first), first)

    def abandon(self) -> None:
        """Stop recording while an exception leaves: nothing is delivered or raised."""
        if self._armed:
            self._armed = False
            _RECORDER.release(self, take=False)
        self._raised.clear()

    def __enter__(self) -> DeferredInterrupts:
        self.arm()
        self.stopping = True
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        first = None
        if self._armed:
            self._armed = False
            first = _RECORDER.release(self, take=exc is None and not self._raised)
        self.stopping = False
        if exc is not None:
            return
        if self._raised:
            raise self._raised[0]
        if first is not None:
            deliver_to(_RECORDER.previous.get(first), first)


def deferred_interrupts() -> DeferredInterrupts:
    """A :class:`DeferredInterrupts` (``with deferred_interrupts() as signals: ...``)."""
    return DeferredInterrupts()
