"""Serve an `EmulatedChain` on a POSIX pseudo-terminal, so any program can open it as a serial port.

The chain follows wall-clock time and replies are written after their Return Delay Time and wire
time, in real time. The line rate follows the baud the client sets on the port (when the kernel
reports a standard rate), so a client at the wrong baud gets silence, as on a real bus.

On a loaded machine this process can be starved of CPU for longer than the Bus Watchdog period
while the host keeps writing. Each loop therefore reads every byte already waiting before it
lets the Bus Watchdog judge the elapsed time, and drops a partial packet only after an idle line
it actually saw: the emulator's own lost time never trips a servo.
"""

from __future__ import annotations

import heapq
import os
import select
import termios
import threading
import time
import tty
from collections.abc import Callable
from types import TracebackType

from snakebot.emulation.chain import EmulatedChain
from snakebot.emulation.errors import EmulationError
from snakebot.emulation.wire import LINE_RATES

Trace = Callable[[str, bytes], None]


class PtyServerCrashedError(RuntimeError):
    """The serving thread died on an exception (a bug): the port no longer answers.

    Not a `SnakebotError`: nothing the user did causes it, so the CLI reports it as a bug.
    """


_RATES = {getattr(termios, f"B{rate}"): rate for rate in LINE_RATES if hasattr(termios, f"B{rate}")}


class PtyServer:
    """A pseudo-terminal whose far end is `chain`; open `device_path` like a USB serial adapter.

    `serve_forever()` blocks; `start()` serves on a daemon thread; `stop()` ends either and closes
    the terminal. `trace(direction, data)` sees "rx" (from the host) and "tx" (to the host) bytes.
    If the serving thread dies, `failure` holds the exception and `check()` (also run when a
    `with` block ends) raises `PtyServerCrashedError` from it. `tick_s` is the longest the server
    sleeps while nothing happens; the chain (and a twin behind it) catches up to the clock
    whenever host bytes arrive or a reply falls due, so an idle emulator costs little CPU and
    the scheduler wakes it promptly on a busy machine.
    """

    def __init__(
        self,
        chain: EmulatedChain,
        *,
        follow_port_baud: bool = True,
        tick_s: float = 0.02,
        trace: Trace | None = None,
    ) -> None:
        if os.name != "posix":
            raise EmulationError("pseudo-terminals need a POSIX system; use dxlemu:// instead")
        self.chain = chain
        self.follow_port_baud = follow_port_baud
        self.tick_s = tick_s
        self.trace = trace
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        self.device_path = os.ttyname(self._slave)
        self._wake_read, self._wake_write = os.pipe()
        self._stopping = threading.Event()
        self._done = threading.Event()
        self._thread: threading.Thread | None = None
        self._serving_thread: threading.Thread | None = None
        self._close_when_done = False
        self._outbox: list[tuple[float, int, bytes]] = []
        self._sequence = 0
        self._closed = False
        self.failure: BaseException | None = None
        self._heard_s = self._quiet_s = 0.0
        self._in_flight = 0

    def __enter__(self) -> PtyServer:
        return self.start()

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.stop()
        if value is None:
            self.check()

    def start(self) -> PtyServer:
        """Serve on a background thread and return self."""
        if self._closed:
            raise EmulationError("this PtyServer was stopped; make a new one")
        if self._thread is None:
            self._thread = threading.Thread(
                target=self._serve_in_thread, name=f"pty-server {self.device_path}", daemon=True
            )
            self._serving_thread = self._thread
            self._thread.start()
        return self

    @property
    def replies_in_flight(self) -> int:
        """Replies scheduled and not yet written to the terminal (0: the host has every reply to
        what the chain has received; hold `chain.lock` to read it together with the chain's
        parser stats, as new replies are scheduled under that lock)."""
        return self._in_flight

    def check(self) -> None:
        """Raise `PtyServerCrashedError` if the serving thread died; otherwise do nothing."""
        if self.failure is not None:
            raise PtyServerCrashedError(
                f"the pty server thread died: {self.failure!r}; {self.device_path} no longer "
                "answers"
            ) from self.failure

    def _serve_in_thread(self) -> None:
        try:
            self.serve_forever()
        except BaseException as exc:  # kept for check(): the thread must not die unnoticed
            self.failure = exc

    def stop(self) -> None:
        """Stop serving and close the terminal (idempotent; safe from a signal handler)."""
        if self._closed or self._stopping.is_set():
            return
        self._stopping.set()
        os.write(self._wake_write, b"x")
        if self._serving_thread is threading.current_thread():
            self._close_when_done = True  # called from inside serve_forever: it closes on exit
            return
        if self._serving_thread is not None:
            self._done.wait(timeout=5.0)
        self._close()

    def serve_forever(self) -> None:
        """Answer the host until `stop()` is called."""
        if self._closed:
            raise EmulationError("this PtyServer was stopped; make a new one")
        if self._serving_thread is None:
            self._serving_thread = threading.current_thread()
        last = self._heard_s = self._quiet_s = time.monotonic()
        try:
            while not self._stopping.is_set():
                polled = time.monotonic()
                data = self._read_pending()
                now = time.monotonic()
                # Bytes found waiting arrived at some unknown moment since `last` (longer ago
                # when this process was starved of CPU): time passes first, then they are fed,
                # and only then may the Bus Watchdog judge the host (chain.advance).
                self.chain.advance(now - last, bytes_waiting=bool(data))
                last = now
                if data:
                    self._on_bytes(data, now)
                else:
                    self._quiet_s = polled
                self._flush_due(now)
                wait = self.tick_s
                if self._outbox:
                    wait = max(0.0, min(wait, self._outbox[0][0] - now))
                select.select([self._master, self._wake_read], [], [], wait)
        finally:
            self._done.set()
            if self._close_when_done:
                self._close()

    def _close(self) -> None:
        if not self._closed:
            self._closed = True
            for fd in (self._master, self._slave, self._wake_read, self._wake_write):
                os.close(fd)

    def _line_baud(self) -> int | None:
        try:
            speed = termios.tcgetattr(self._slave)[5]
        except termios.error:
            return None
        return _RATES.get(speed)

    def _read_pending(self) -> bytes:
        """Every byte the host has written so far (b"" if none); never blocks."""
        chunks = []
        while select.select([self._master], [], [], 0)[0]:
            try:
                chunk = os.read(self._master, 4096)
            except OSError:
                break
            if not chunk:
                break
            chunks.append(chunk)
        return b"".join(chunks)

    def _on_bytes(self, data: bytes, arrived: float) -> None:
        """Feed host bytes read at `arrived` and schedule the replies in real time."""
        if self.trace is not None:
            self.trace("rx", data)
        baud = self._line_baud() if self.follow_port_baud else None
        # The line was surely idle from the last bytes read to the last poll that found none;
        # a starved poll loop cannot claim more (a partial packet is dropped only after that).
        idle_s = max(0.0, self._quiet_s - self._heard_s)
        self._heard_s = arrived
        with self.chain.lock:
            if baud is not None:
                self.chain.baud = baud
            for reply in self.chain.receive(data, idle_s=idle_s):
                self._sequence += 1
                due = arrived + reply.end_s(self.chain.baud)
                heapq.heappush(self._outbox, (due, self._sequence, reply.data))
                self._in_flight += 1

    def _flush_due(self, now: float) -> None:
        while self._outbox and self._outbox[0][0] <= now:
            data = heapq.heappop(self._outbox)[2]
            if self.trace is not None:
                self.trace("tx", data)
            try:
                os.write(self._master, data)
            except OSError:
                return
            finally:
                self._in_flight -= 1
