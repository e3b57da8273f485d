"""Feetech FT-SCS codec (STS/SMS/SCS servos), written apart from `scservo_sdk`.

The framing is Dynamixel Protocol 1.0's byte for byte (``FF FF ID LEN INST P1..PN CHK``, LEN =
N + 2, ``CHK = ~(ID + LEN + INST + params) & 0xFF``; Feetech wiki ``protocol/ft-scs.md``), so the
packets, the checksum and the stream parser are `protocol1`'s. What differs is the instruction
set (0x06 is Parameter Recovery, 0x0A Reset, 0x82 Sync Read, no Bulk Read) and the status byte:
its bits report the servo's condition only (voltage, angle sensor, overheat, overcurrent,
overload); there is no checksum, instruction or range bit. References: Feetech wiki
``docs/en/reference/protocol/ft-scs.md``; /work/shared/reference/servo-families.md §1.
"""

from __future__ import annotations

from enum import IntEnum, IntFlag

from snakebot.emulation.protocol1 import (
    BROADCAST_ID,
    MAX_PACKET_BYTES,
    Packet,
    StreamParser,
    checksum,
    frame,
    parse_packets,
)

MAX_ID = 0xFD
"""The highest ID a servo can hold (253); the SDK's own MAX_ID is 0xFC."""

__all__ = [
    "BROADCAST_ID",
    "MAX_ID",
    "MAX_PACKET_BYTES",
    "ErrorBit",
    "Instruction",
    "Packet",
    "StreamParser",
    "build_instruction",
    "build_status",
    "checksum",
    "parse_packets",
]


class Instruction(IntEnum):
    """FT-SCS instruction codes (Feetech wiki ft-scs.md §4)."""

    PING = 0x01
    READ = 0x02
    WRITE = 0x03
    REG_WRITE = 0x04
    ACTION = 0x05
    RECOVERY = 0x06
    """Parameter recovery: every parameter back to its factory value except the ID."""
    RESTART = 0x08
    """Restart: no status packet; the servo boots again."""
    BACKUP = 0x09
    """Parameter backup: the image a later recovery restores."""
    RESET = 0x0A
    """Status reset: the turn count is forgotten."""
    OFSCAL = 0x0B
    """Position calibration: the present position becomes the middle (2048) or the value given."""
    SYNC_READ = 0x82
    SYNC_WRITE = 0x83


class ErrorBit(IntFlag):
    """The status packet's error byte (the SDK's ERRBIT_* constants; the bits of Servo status
    (65), Unload condition (19) and LED alarm condition (20) on an STS)."""

    NONE = 0x00
    VOLTAGE = 0x01
    ANGLE = 0x02
    OVERHEAT = 0x04
    OVERCURRENT = 0x08
    OVERLOAD = 0x20


def build_instruction(servo_id: int, instruction: int, params: bytes | bytearray = b"") -> bytes:
    """Return the wire bytes of an instruction packet."""
    return frame(servo_id, instruction, params)


def build_status(servo_id: int, error: int, params: bytes | bytearray = b"") -> bytes:
    """Return the wire bytes of a status packet with error byte `error` (bit 7 is always 0: the
    SDK drops a status whose error byte exceeds 0x7F)."""
    return frame(servo_id, error & 0x7F, params)
