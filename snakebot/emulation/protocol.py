"""Dynamixel Protocol 2.0 codec, written apart from the ROBOTIS SDK so one bug cannot hide another.

CRC-16 (poly 0x8005), byte stuffing, instruction/status packet building and an incremental stream
parser that finds packets in arbitrary chunks and resyncs after garbage. Reference: e-Manual
`docs/en/dxl/protocol2.md`; /work/shared/reference/dynamixel.md §1.1-1.5.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from enum import IntEnum

from snakebot.emulation.stream import FrameStream

HEADER = b"\xff\xff\xfd\x00"
BROADCAST_ID = 0xFE
MAX_ID = 0xFC
MAX_PACKET_BYTES = 1024
ALERT_BIT = 0x80
CRC_POLYNOMIAL = 0x8005


class Instruction(IntEnum):
    """Protocol 2.0 instruction codes."""

    PING = 0x01
    READ = 0x02
    WRITE = 0x03
    REG_WRITE = 0x04
    ACTION = 0x05
    FACTORY_RESET = 0x06
    REBOOT = 0x08
    CLEAR = 0x10
    STATUS = 0x55
    SYNC_READ = 0x82
    SYNC_WRITE = 0x83
    FAST_SYNC_READ = 0x8A
    BULK_READ = 0x92
    BULK_WRITE = 0x93
    FAST_BULK_READ = 0x9A


class StatusError(IntEnum):
    """Error numbers carried in bits 0-6 of a status packet's error byte (bit 7 is the alert)."""

    NONE = 0x00
    RESULT_FAIL = 0x01
    INSTRUCTION = 0x02
    CRC = 0x03
    DATA_RANGE = 0x04
    DATA_LENGTH = 0x05
    DATA_LIMIT = 0x06
    ACCESS = 0x07


def _crc_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ CRC_POLYNOMIAL) if crc & 0x8000 else (crc << 1)
        table.append(crc & 0xFFFF)
    return tuple(table)


CRC_TABLE = _crc_table()


def crc16(data: bytes | bytearray, crc: int = 0) -> int:
    """CRC-16/BUYPASS (poly 0x8005, init 0, unreflected) of `data`, continuing from `crc`."""
    for byte in data:
        crc = ((crc << 8) ^ CRC_TABLE[((crc >> 8) ^ byte) & 0xFF]) & 0xFFFF
    return crc


def stuff(body: bytes | bytearray) -> bytes:
    """Insert 0xFD after every FF FF FD in `body` (instruction byte through last parameter)."""
    out = bytearray()
    run = 0
    for byte in body:
        out.append(byte)
        if byte == 0xFD and run >= 2:
            out.append(0xFD)
        run = run + 1 if byte == 0xFF else 0
    return bytes(out)


def unstuff(body: bytes | bytearray) -> bytes:
    """Remove the 0xFD that stuffing added after each FF FF FD."""
    out = bytearray()
    index = 0
    while index < len(body):
        out.append(body[index])
        if out[-3:] == b"\xff\xff\xfd" and index + 1 < len(body) and body[index + 1] == 0xFD:
            index += 1
        index += 1
    return bytes(out)


def frame(servo_id: int, body: bytes | bytearray, *, stuffed: bool = True) -> bytes:
    """Wrap a body (instruction or 0x55+error, then parameters) into header, ID, length and CRC."""
    payload = stuff(body) if stuffed else bytes(body)
    length = len(payload) + 2
    head = HEADER + bytes([servo_id, length & 0xFF, length >> 8]) + payload
    crc = crc16(head)
    return head + bytes([crc & 0xFF, crc >> 8])


def build_instruction(servo_id: int, instruction: int, params: bytes | bytearray = b"") -> bytes:
    """Return the wire bytes of an instruction packet."""
    return frame(servo_id, bytes([instruction]) + bytes(params))


def build_status(servo_id: int, error: int, params: bytes | bytearray = b"") -> bytes:
    """Return the wire bytes of a status packet (stuffed, as every non-fast status packet is)."""
    return frame(servo_id, bytes([Instruction.STATUS, error]) + bytes(params))


def fast_status_header(entries: Sequence[tuple[int, int, bytes]]) -> bytes:
    """The bytes a Fast Sync/Bulk Read reply starts with: header, ID 0xFE, LEN of the whole
    packet (for `entries` of (servo ID, error byte, data)) and the 0x55 instruction."""
    length = 1 + sum(len(data) + 4 for _, _, data in entries)
    return HEADER + bytes([BROADCAST_ID, length & 0xFF, length >> 8, Instruction.STATUS])


def fast_reply_bytes(lengths: Iterable[int]) -> int:
    """Wire bytes of a Fast Sync/Bulk Read reply with these data lengths, one per servo:
    header(7), 0x55, then error, ID, data and CRC per servo, unstuffed (8 + N·4 + ΣL)."""
    return 8 + sum(length + 4 for length in lengths)


def fast_status_segment(crc_so_far: int, servo_id: int, error: int, data: bytes) -> bytes:
    """One servo's part of a fast reply: error, ID, data, then the CRC of the packet so far
    (`crc_so_far` is the CRC of every byte sent before this part)."""
    body = bytes([error, servo_id]) + data
    crc = crc16(body, crc_so_far)
    return body + bytes([crc & 0xFF, crc >> 8])


def fast_status_segments(entries: Sequence[tuple[int, int, bytes]]) -> list[bytes]:
    """Split a Fast Sync/Bulk Read reply into the bytes each servo sends, in order.

    `entries` holds (servo ID, error byte, data). The first segment carries the header (ID 0xFE,
    LEN for the whole packet, 0x55); each segment ends with the CRC of the packet so far, so the
    last one ends with the packet CRC. Fast replies are not stuffed (reference §1.3, §1.5).
    """
    header = fast_status_header(entries)
    crc = crc16(header)
    segments: list[bytes] = []
    for servo_id, error, data in entries:
        segment = fast_status_segment(crc, servo_id, error, data)
        crc = crc16(segment, crc)
        segments.append(header + segment if not segments else segment)
    return segments


def build_fast_status(entries: Sequence[tuple[int, int, bytes]]) -> bytes:
    """Return the whole Fast Sync/Bulk Read reply for (servo ID, error, data) entries."""
    return b"".join(fast_status_segments(entries))


@dataclass(frozen=True)
class Packet:
    """A parsed packet: `instruction` is 0x55 for status packets, whose `params` start with ERR."""

    servo_id: int
    instruction: int
    params: bytes

    @property
    def is_status(self) -> bool:
        """Whether this is a status (reply) packet."""
        return self.instruction == Instruction.STATUS

    @property
    def error(self) -> int:
        """The status error byte (0 for instruction packets)."""
        return self.params[0] if self.is_status and self.params else 0

    @property
    def data(self) -> bytes:
        """Status parameters after the error byte, or the instruction's parameters."""
        return self.params[1:] if self.is_status else self.params


class StreamParser(FrameStream[Packet]):
    """Find Protocol 2.0 packets in a byte stream fed in arbitrary chunks; never raises on input.

    Bytes before a header are dropped; a header with an invalid ID, length or CRC costs one byte and
    the search resumes after it. A partial packet older than `stale_after_s` (no byte for that long)
    is discarded, as a servo's receiver times out.
    """

    def _next(self) -> tuple[Packet | None, int]:
        """Return (packet or None, bytes to consume); (None, 0) means wait for more bytes."""
        buf = self._buffer
        start = buf.find(b"\xff\xff\xfd")
        if start < 0:
            keep = 2 if buf.endswith(b"\xff\xff") else 1 if buf.endswith(b"\xff") else 0
            self.stats.dropped_bytes += len(buf) - keep
            return None, len(buf) - keep
        if start > 0:
            self.stats.dropped_bytes += start
            return None, start
        if len(buf) < 7:
            return None, 0
        servo_id, length = buf[4], buf[5] | (buf[6] << 8)
        valid_id = servo_id <= MAX_ID or servo_id == BROADCAST_ID
        if buf[3] != 0x00 or not valid_id or not 3 <= length <= MAX_PACKET_BYTES - 7:
            self.stats.bad_headers += 1
            self.stats.dropped_bytes += 1
            return None, 1
        total = 7 + length
        if len(buf) < total:
            return None, 0
        if crc16(buf[: total - 2]) != buf[total - 2] | (buf[total - 1] << 8):
            self.stats.crc_errors += 1
            self.stats.dropped_bytes += 1
            return None, 1
        body = bytes(buf[7 : total - 2])
        fast_reply = servo_id == BROADCAST_ID and body[:1] == bytes([Instruction.STATUS])
        body = body if fast_reply else unstuff(body)
        self.stats.packets += 1
        return Packet(servo_id, body[0], body[1:]), total


def parse_packets(data: bytes | bytearray) -> list[Packet]:
    """Return every valid packet in `data` (a convenience around a fresh StreamParser)."""
    return StreamParser(stale_after_s=None).feed(data)
