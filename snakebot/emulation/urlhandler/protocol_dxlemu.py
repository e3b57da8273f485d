"""pyserial port for `dxlemu://<name>[?time=virtual|wall][&poll_ms=1]`: an in-process chain.

Register the chain first (`snakebot.emulation.register_chain`). Replies arrive after the servos'
Return Delay Time plus wire time at the port's baud rate.

- `time=virtual` (default): the chain's clock is the only clock. Writing advances it by the
  instruction's wire time; a read that finds nothing advances it to the next reply or by `poll_ms`,
  so a missing reply times out after the SDK's ~34 ms of *virtual* time, in microseconds of CPU.
  `clock_ms()` exposes that clock (EmulatedPortHandler reports it to the SDK).
- `time=wall`: the chain follows `time.monotonic()`; replies wait for real time to pass.
"""

from __future__ import annotations

import heapq
import time
import urllib.parse
from typing import Any

from serial.serialutil import PortNotOpenError, SerialBase, SerialException, to_bytes

from snakebot.emulation.chain import EmulatedChain
from snakebot.emulation.errors import EmulationError
from snakebot.emulation.registry import SCHEME, TIME_MODES, lookup_chain
from snakebot.emulation.wire import LINE_RATES, byte_time_s

_GRAMMAR = f"{SCHEME}://<name>[?time={'|'.join(TIME_MODES)}][&poll_ms=<float>]"


def _parse(url: str) -> tuple[EmulatedChain, str, float]:
    parts = urllib.parse.urlsplit(url)
    try:
        if parts.scheme != SCHEME or not parts.netloc:
            raise EmulationError(f"not a {SCHEME} URL")
        options = urllib.parse.parse_qs(parts.query, strict_parsing=bool(parts.query))
        unknown = set(options) - {"time", "poll_ms"}
        if unknown:
            raise EmulationError(f"unknown option(s) {sorted(unknown)}")
        mode = options.get("time", ["virtual"])[-1]
        if mode not in TIME_MODES:
            raise EmulationError(f"time must be one of {TIME_MODES}")
        poll_s = float(options.get("poll_ms", ["1"])[-1]) / 1000.0
        if not poll_s > 0.0:
            raise EmulationError("poll_ms must be positive")
        return lookup_chain(parts.netloc), mode, poll_s
    except (EmulationError, ValueError) as error:
        raise SerialException(f"expected {_GRAMMAR}, got {url!r}: {error}") from error


class Serial(SerialBase):  # type: ignore[misc]
    """A serial port whose far end is an `EmulatedChain` (see the module docstring for time)."""

    is_open: bool

    BAUDRATES = LINE_RATES

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self._chain: EmulatedChain | None = None
        self._virtual = True
        self._poll_s = 0.001
        self._rx = bytearray()
        self._in_flight: list[tuple[float, int, bytes]] = []
        self._sequence = 0
        self._wall_anchor = 0.0
        super().__init__(*args, **kwargs)

    # ------------------------------------------------------------------ pyserial plumbing
    def open(self) -> None:
        """Connect to the registered chain named in the URL."""
        if self.is_open:
            raise SerialException("Port is already open.")
        if self._port is None:
            raise SerialException("Port must be configured before it can be used.")
        self._chain, mode, self._poll_s = _parse(str(self.portstr))
        self._virtual = mode == "virtual"
        self._wall_anchor = time.monotonic()
        self.is_open = True
        self._reconfigure_port()
        self.reset_input_buffer()

    def close(self) -> None:
        """Disconnect; replies still in flight are lost."""
        self.is_open = False
        self._rx.clear()
        self._in_flight.clear()

    def _reconfigure_port(self) -> None:
        if self._chain is not None and self.is_open:
            with self._chain.lock:
                self._chain.baud = int(self._baudrate)

    def _update_rts_state(self) -> None:
        """No modem lines on the emulated bus."""

    def _update_dtr_state(self) -> None:
        """No modem lines on the emulated bus."""

    def _update_break_state(self) -> None:
        """No break condition on the emulated bus."""

    def _chain_or_raise(self) -> EmulatedChain:
        if not self.is_open or self._chain is None:
            raise PortNotOpenError()
        return self._chain

    # ------------------------------------------------------------------ time
    def clock_ms(self) -> float:
        """The bus clock in ms: the chain's virtual time, or wall time in `time=wall` mode."""
        chain = self._chain_or_raise()
        return chain.now_s * 1000.0 if self._virtual else time.time() * 1000.0

    def _sync_wall(self, chain: EmulatedChain) -> None:
        if not self._virtual:
            now = time.monotonic()
            chain.advance(now - self._wall_anchor)
            self._wall_anchor = now

    def _pump(self, chain: EmulatedChain) -> None:
        while self._in_flight and self._in_flight[0][0] <= chain.now_s + 1e-12:
            self._rx += heapq.heappop(self._in_flight)[2]

    def _idle(self, chain: EmulatedChain) -> None:
        """Nothing to read: let virtual time move to the next reply, or by one poll period."""
        if self._virtual:
            step = self._poll_s
            if self._in_flight:
                step = min(step, max(self._in_flight[0][0] - chain.now_s, 0.0))
            chain.advance(step)
        self._pump(chain)

    # ------------------------------------------------------------------ I/O
    @property
    def in_waiting(self) -> int:
        """Bytes that have arrived and wait to be read."""
        chain = self._chain_or_raise()
        with chain.lock:
            self._sync_wall(chain)
            self._pump(chain)
            if not self._rx and self._in_flight:
                self._idle(chain)
        return len(self._rx)

    def read(self, size: int = 1) -> bytes:
        """Return up to `size` arrived bytes, waiting at most `timeout` (bus time)."""
        chain = self._chain_or_raise()
        timeout = self._timeout
        with chain.lock:
            self._sync_wall(chain)
            self._pump(chain)
            start = self.clock_ms()
            while len(self._rx) < size:
                if timeout is None and self._virtual and not self._in_flight:
                    break
                if (
                    timeout is not None
                    and timeout != 0
                    and self.clock_ms() - start >= timeout * 1e3
                ):
                    break
                if not self._virtual and timeout != 0:
                    time.sleep(min(self._poll_s, 0.001))
                    self._sync_wall(chain)
                self._idle(chain)
                if timeout == 0:
                    break
            data = bytes(self._rx[:size])
            del self._rx[:size]
        return data

    def write(self, data: Any) -> int:
        """Send bytes to the servos; their replies are scheduled on the bus clock."""
        chain = self._chain_or_raise()
        payload = to_bytes(data)
        with chain.lock:
            self._sync_wall(chain)
            wire_s = len(payload) * byte_time_s(chain.baud)
            if self._virtual:
                chain.advance(wire_s)
            end_s = chain.now_s if self._virtual else chain.now_s + wire_s
            for reply in chain.receive(payload):
                self._sequence += 1
                arrival = end_s + reply.end_s(chain.baud)
                heapq.heappush(self._in_flight, (arrival, self._sequence, reply.data))
        return len(payload)

    def reset_input_buffer(self) -> None:
        """Discard bytes that have arrived; replies still on the wire arrive later."""
        chain = self._chain_or_raise()
        with chain.lock:
            self._sync_wall(chain)
            self._pump(chain)
            self._rx.clear()

    def reset_output_buffer(self) -> None:
        """Nothing is buffered on the way out."""
        self._chain_or_raise()

    def flush(self) -> None:
        """Writes are delivered immediately."""
        self._chain_or_raise()
