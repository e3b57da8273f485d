"""Packets out of a byte stream fed in arbitrary chunks: the buffering both codecs share.

A protocol's parser subclasses :class:`FrameStream` and says only how a packet starts and ends
(``_next``); the buffer, the receiver's timeout on a partial packet and the counts live here.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Generic, TypeVar

P = TypeVar("P")


@dataclass
class ParserStats:
    """Counts of what the stream parser took in and threw away, for diagnostics and tests.

    ``crc_errors`` counts failed integrity checks: Protocol 2.0's CRC, Protocol 1.0's checksum.
    """

    received_bytes: int = 0
    packets: int = 0
    dropped_bytes: int = 0
    crc_errors: int = 0
    bad_headers: int = 0
    stale_resets: int = 0


class FrameStream(ABC, Generic[P]):
    """Find packets in a byte stream; never raises on input.

    A partial packet older than ``stale_after_s`` (no byte for that long) is discarded, as a
    servo's receiver times out; None keeps it forever.
    """

    def __init__(self, *, stale_after_s: float | None = 0.02) -> None:
        self._buffer = bytearray()
        self._last_byte_s = 0.0
        self._stale_after_s = stale_after_s
        self.stats = ParserStats()

    def reset(self) -> None:
        """Forget any partial packet."""
        self.stats.dropped_bytes += len(self._buffer)
        self._buffer.clear()

    @property
    def pending(self) -> int:
        """Bytes held while waiting for the rest of a packet."""
        return len(self._buffer)

    def feed(
        self, data: bytes | bytearray, now_s: float = 0.0, *, idle_s: float | None = None
    ) -> list[P]:
        """Add received bytes (at time `now_s`) and return every packet they complete.

        `idle_s`: how long the line was idle before `data` (default: `now_s` minus the time of
        the last bytes); a partial packet is discarded when it exceeds `stale_after_s`.
        """
        stale = self._stale_after_s
        if idle_s is None:
            idle_s = now_s - self._last_byte_s
        if self._buffer and stale is not None and idle_s > stale:
            self.stats.stale_resets += 1
            self.reset()
        if data:
            self._last_byte_s = now_s
        self._buffer += data
        self.stats.received_bytes += len(data)
        packets: list[P] = []
        while True:
            packet, consumed = self._next()
            if consumed == 0:
                return packets
            del self._buffer[:consumed]
            if packet is not None:
                packets.append(packet)

    @abstractmethod
    def _next(self) -> tuple[P | None, int]:
        """Return (packet or None, bytes to consume) from the buffer's start; (None, 0) means
        wait for more bytes."""
