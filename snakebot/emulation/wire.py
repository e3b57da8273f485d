"""The half-duplex wire: byte timing and what a UART receives when two servos talk at once."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

BITS_PER_BYTE = 10
# Serial line rates (bit/s) a host may set on the emulated port; 4.5 Mbps is the X-series top,
# 76 800, 128 000 and 250 000 are Feetech's (wiki memory-sts.md baud table).
LINE_RATES = (
    9600,
    19200,
    38400,
    57600,
    76800,
    115200,
    128000,
    230400,
    250000,
    460800,
    500000,
    576000,
    921600,
    1000000,
    1152000,
    2000000,
    2500000,
    3000000,
    3500000,
    4000000,
    4500000,
)
_OVERSAMPLE = 16


def byte_time_s(baud: int) -> float:
    """Seconds one byte takes on the wire at `baud` (8N1: 10 bits)."""
    return BITS_PER_BYTE / baud


@dataclass(frozen=True)
class BusReply:
    """Bytes the servos put on the wire, starting `start_s` after the instruction's last byte."""

    start_s: float
    data: bytes

    def end_s(self, baud: int) -> float:
        """When the last byte has arrived, relative to the instruction's end."""
        return self.start_s + len(self.data) * byte_time_s(baud)


def _bits(byte: int) -> list[int]:
    return [0, *((byte >> k) & 1 for k in range(8)), 1]


def _receive(line: bytearray) -> bytes:
    """Decode an oversampled line (1 = idle) as a UART does: start edge, then mid-bit samples."""
    out = bytearray()
    half, step = _OVERSAMPLE // 2, _OVERSAMPLE
    index = 1
    while index < len(line):
        if not (line[index - 1] == 1 and line[index] == 0):
            index += 1
            continue
        centre = index + half
        if centre >= len(line) or line[centre] != 0:
            index += 1
            continue
        value = 0
        for bit in range(8):
            sample = centre + step * (bit + 1)
            if sample < len(line) and line[sample]:
                value |= 1 << bit
        out.append(value)
        index = centre + step * 9
    return bytes(out)


def collide(replies: Sequence[BusReply], baud: int) -> BusReply:
    """Merge overlapping replies as a receiver sees them: low if any driver pulls the line low."""
    start = min(r.start_s for r in replies)
    samples_per_s = baud * _OVERSAMPLE
    offsets = [round((r.start_s - start) * samples_per_s) for r in replies]
    length = max(
        o + len(r.data) * BITS_PER_BYTE * _OVERSAMPLE for o, r in zip(offsets, replies, strict=True)
    )
    line = bytearray([1]) * (length + _OVERSAMPLE + 1)
    for offset, reply in zip(offsets, replies, strict=True):
        position = offset + 1
        for byte in reply.data:
            for level in _bits(byte):
                if not level:
                    line[position : position + _OVERSAMPLE] = bytes(_OVERSAMPLE)
                position += _OVERSAMPLE
    return BusReply(start, _receive(line))


def merge_collisions(replies: Sequence[BusReply], baud: int) -> list[BusReply]:
    """Sort replies by start and replace each group overlapping on the wire by its collision."""
    merged: list[BusReply] = []
    group: list[BusReply] = []
    group_end = float("-inf")
    for reply in sorted(replies, key=lambda r: r.start_s):
        if group and reply.start_s < group_end:
            group.append(reply)
        else:
            if group:
                merged.append(group[0] if len(group) == 1 else collide(group, baud))
            group = [reply]
        group_end = max(group_end, reply.end_s(baud)) if len(group) > 1 else reply.end_s(baud)
    if group:
        merged.append(group[0] if len(group) == 1 else collide(group, baud))
    return merged
