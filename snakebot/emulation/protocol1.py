"""Dynamixel Protocol 1.0 codec, written apart from the ROBOTIS SDK so one bug cannot hide another.

Packets are ``FF FF ID LEN INST P1..PN CHK`` (instruction) and ``FF FF ID LEN ERR D1..DN CHK``
(status): LEN counts INST/ERR, the parameters and the checksum; ``CHK = ~(ID + LEN + INST +
params) & 0xFF``. No byte stuffing, no CRC, no status instruction: a status packet looks like an
instruction packet whose instruction byte is the error byte. Reference: e-Manual
``docs/en/dxl/protocol1.md``; /work/shared/reference/servo-families.md §3.1.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum, IntFlag

from snakebot.emulation.stream import FrameStream

HEADER = b"\xff\xff"
BROADCAST_ID = 0xFE
MAX_ID = 0xFD
MAX_PACKET_BYTES = 250
"""The SDK's TXPACKET_MAX_LEN/RXPACKET_MAX_LEN for Protocol 1.0: no packet is longer."""
MIN_LENGTH = 2


class Instruction(IntEnum):
    """Protocol 1.0 instruction codes (the e-Manual's instruction table)."""

    PING = 0x01
    READ = 0x02
    WRITE = 0x03
    REG_WRITE = 0x04
    ACTION = 0x05
    FACTORY_RESET = 0x06
    SYNC_WRITE = 0x83
    BULK_READ = 0x92


class ErrorBit(IntFlag):
    """The status packet's error byte: one bit per fault (bit 7 is always 0)."""

    NONE = 0x00
    INPUT_VOLTAGE = 0x01
    ANGLE_LIMIT = 0x02
    OVERHEATING = 0x04
    RANGE = 0x08
    CHECKSUM = 0x10
    OVERLOAD = 0x20
    INSTRUCTION = 0x40


def checksum(body: bytes | bytearray) -> int:
    """The one's complement of the low byte of the sum of ID, LEN, INST/ERR and parameters."""
    return ~sum(body) & 0xFF


def frame(servo_id: int, first: int, params: bytes | bytearray = b"") -> bytes:
    """Wrap ID, the instruction (or error) byte and parameters into header, LEN and checksum."""
    body = bytes([servo_id, len(params) + 2, first]) + bytes(params)
    return HEADER + body + bytes([checksum(body)])


def build_instruction(servo_id: int, instruction: int, params: bytes | bytearray = b"") -> bytes:
    """Return the wire bytes of an instruction packet."""
    return frame(servo_id, instruction, params)


def build_status(servo_id: int, error: int, params: bytes | bytearray = b"") -> bytes:
    """Return the wire bytes of a status packet with error byte `error`."""
    return frame(servo_id, error & 0x7F, params)


@dataclass(frozen=True)
class Packet:
    """A parsed Protocol 1.0 packet. `first` is the instruction byte (the error byte when this
    is a status packet: the framing cannot tell); `intact` is False when the checksum failed,
    which a servo answers with the Checksum error bit."""

    servo_id: int
    first: int
    params: bytes
    intact: bool = True

    @property
    def instruction(self) -> int:
        """The instruction code."""
        return self.first

    @property
    def error(self) -> int:
        """The error byte, read as a status packet."""
        return self.first


class StreamParser(FrameStream[Packet]):
    """Find Protocol 1.0 packets in a byte stream fed in arbitrary chunks; never raises on input.

    Bytes before a header are dropped; a header with an invalid ID or length costs one byte and
    the search resumes after it. A complete frame whose checksum fails is returned once with
    ``intact=False`` (a servo answers it with the Checksum bit) and also costs only one byte, so
    a real packet hidden inside garbage is still found. A partial packet older than
    `stale_after_s` is discarded, as a servo's receiver times out. `stats.crc_errors` counts
    checksum failures (the name is shared with the Protocol 2.0 parser's stats).
    """

    def _next(self) -> tuple[Packet | None, int]:
        """Return (packet or None, bytes to consume); (None, 0) means wait for more bytes."""
        buf = self._buffer
        start = buf.find(HEADER)
        if start < 0:
            keep = 1 if buf.endswith(b"\xff") else 0
            self.stats.dropped_bytes += len(buf) - keep
            return None, len(buf) - keep
        if start > 0:
            self.stats.dropped_bytes += start
            return None, start
        if len(buf) < 4:
            return None, 0
        servo_id, length = buf[2], buf[3]
        if servo_id == 0xFF or not MIN_LENGTH <= length <= MAX_PACKET_BYTES - 4:
            self.stats.bad_headers += 1
            self.stats.dropped_bytes += 1
            return None, 1
        total = 4 + length
        if len(buf) < total:
            return None, 0
        params = bytes(buf[5 : total - 1])
        if checksum(buf[2 : total - 1]) != buf[total - 1]:
            self.stats.crc_errors += 1
            self.stats.dropped_bytes += 1
            return Packet(servo_id, buf[4], params, intact=False), 1
        self.stats.packets += 1
        return Packet(servo_id, buf[4], params), total


def parse_packets(data: bytes | bytearray) -> list[Packet]:
    """Return every intact packet in `data` (a convenience around a fresh StreamParser)."""
    return [p for p in StreamParser(stale_after_s=None).feed(data) if p.intact]
