"""Protocol 1.0 fuzz inputs for the emulated bus, and a reference reading of what they contain.

Built from the Protocol 1.0 document (e-Manual protocol1.md; servo-families.md §3.1), not from
the emulator's codec: the checksum is written out here once more. Each input is drawn from
`random.Random(seed, index)` alone, so any one can be replayed.

Families: random bytes, field-aware packets (the P1 instruction set, the ones it lacks, and
absurd fields), bit flips, truncations, wrong LEN fields, bad checksums, splices, streams, and
Protocol 2.0 packets mixed in (which a Protocol 1.0 servo must ignore).
"""

from __future__ import annotations

import random
from collections.abc import Callable

from fuzz_packets import Candidate
from fuzz_packets import packet as packet2

HEADER = b"\xff\xff"
BROADCAST = 0xFE
MAX_PACKET = 250  # the SDK's Protocol 1.0 TX/RX buffers
MAX_LEN = MAX_PACKET - 4
PING, READ, WRITE, REG_WRITE, ACTION, RESET, SYNC_WRITE, BULK_READ = 1, 2, 3, 4, 5, 6, 0x83, 0x92
ABSENT = (0x08, 0x10, 0x55, 0x82, 0x8A, 0x93, 0x9A)  # Protocol 2.0 only: Instruction error
INSTRUCTIONS = (PING, READ, WRITE, REG_WRITE, ACTION, RESET, SYNC_WRITE, BULK_READ, *ABSENT)
_WEIGHTS = [
    6 if i == WRITE else 3 if i in (READ, BULK_READ, SYNC_WRITE) else 1 for i in INSTRUCTIONS
]
READ_ONLY = frozenset({PING, READ, BULK_READ, *ABSENT})
"""Instructions that change no control-table byte (present values aside)."""
CHECKSUM_BIT = 0x10

# (address, size) of AX-12A items (e-Manual ax-12a.md) and X-series items below 256.
ITEMS = (
    (0, 2),
    (2, 1),
    (3, 1),
    (4, 1),
    (5, 1),
    (6, 2),
    (8, 2),
    (11, 1),
    (12, 1),
    (13, 1),
    (14, 2),
    (16, 1),
    (17, 1),
    (18, 1),
    (24, 1),
    (25, 1),
    (26, 1),
    (27, 1),
    (28, 1),
    (29, 1),
    (30, 2),
    (32, 2),
    (34, 2),
    (36, 2),
    (38, 2),
    (40, 2),
    (42, 1),
    (43, 1),
    (44, 1),
    (46, 1),
    (47, 1),
    (48, 2),
    (7, 1),
    (9, 1),
    (10, 1),
    (20, 4),
    (31, 1),
    (44, 4),
    (48, 4),
    (64, 1),
    (65, 1),
    (68, 1),
    (70, 1),
    (84, 2),
    (98, 1),
    (104, 4),
    (112, 4),
    (116, 4),
    (132, 4),
    (168, 2),
    (224, 1),
)


def checksum(body: bytes) -> int:
    """~(ID + LEN + INST + params) & 0xFF."""
    return ~sum(body) & 0xFF


def packet(servo_id: int, instruction: int, params: bytes) -> bytes:
    """A well-formed Protocol 1.0 instruction packet."""
    body = bytes([servo_id & 0xFF, (len(params) + 2) & 0xFF, instruction]) + params
    return HEADER + body + bytes([checksum(body)])


def candidates(data: bytes) -> list[Candidate]:
    """Every place in `data` where a receiver could find a valid Protocol 1.0 packet: FF FF,
    ID other than 0xFF, 2 <= LEN <= 246, all bytes present, checksum right. `instruction` holds
    the error byte where the packet is a status."""
    found = []
    start = data.find(HEADER)
    while start >= 0:
        if start + 4 <= len(data):
            servo_id, length = data[start + 2], data[start + 3]
            end = start + 4 + length
            if (
                servo_id != 0xFF
                and 2 <= length <= MAX_LEN
                and end <= len(data)
                and checksum(data[start + 2 : end - 1]) == data[end - 1]
            ):
                found.append(
                    Candidate(start, servo_id, data[start + 4], bytes(data[start + 5 : end - 1]))
                )
        start = data.find(HEADER, start + 1)
    return found


def framed_ids(data: bytes) -> set[int]:
    """IDs of every complete frame in `data`, whatever its checksum (a servo answers a bad
    checksum with the Checksum bit)."""
    ids = set()
    start = data.find(HEADER)
    while start >= 0:
        if start + 4 <= len(data):
            length = data[start + 3]
            if (
                data[start + 2] != 0xFF
                and 2 <= length <= MAX_LEN
                and start + 4 + length <= len(data)
            ):
                ids.add(data[start + 2])
        start = data.find(HEADER, start + 1)
    return ids


class Inputs1:
    """Draws Protocol 1.0 fuzz inputs for a chain whose servos have `ids`."""

    def __init__(self, ids: tuple[int, ...]) -> None:
        self.ids = ids
        self._families: tuple[tuple[str, Callable[[random.Random], bytes], int], ...] = (
            ("random", self.random_bytes, 10),
            ("field", self.valid, 32),
            ("bitflip", self.bit_flip, 12),
            ("truncated", self.truncated, 8),
            ("length", self.wrong_length, 10),
            ("checksum", self.bad_checksum, 8),
            ("splice", self.splice, 10),
            ("stream", self.stream, 5),
            ("protocol2", self.protocol2, 5),
        )
        self._weights = [w for _, _, w in self._families]

    def make(self, seed: int, index: int) -> tuple[str, bytes]:
        """Input number `index` of campaign `seed`: (family, bytes)."""
        rng = random.Random(seed * 1_000_003 + index)
        name, build, _ = rng.choices(self._families, self._weights)[0]
        return name, build(rng)

    def _id(self, rng: random.Random) -> int:
        pick = rng.random()
        if pick < 0.6:
            return rng.choice(self.ids)
        if pick < 0.85:
            return BROADCAST
        return rng.choice((0, 253, 255, rng.randrange(256)))

    def _address(self, rng: random.Random) -> int:
        return rng.choice(ITEMS)[0] if rng.random() < 0.8 else rng.randrange(256)

    def _length(self, rng: random.Random) -> int:
        pick = rng.random()
        if pick < 0.75:
            return rng.choice((1, 2, 4, 6, rng.randrange(1, 16)))
        return rng.choice((0, 243, 244, 245, 255, rng.randrange(256)))

    def _value(self, rng: random.Random, size: int) -> bytes:
        pick = rng.random()
        if pick < 0.3:
            return bytes(rng.randrange(256) for _ in range(size))
        if pick < 0.55:
            value = rng.randrange(0, 20)
        elif pick < 0.8:
            value = rng.randrange(0, 4096)
        else:
            return bytes([rng.choice((0, 1, 0x7F, 0x80, 0xFE, 0xFF))] * size)
        return (value % (1 << (8 * size))).to_bytes(size, "little")

    def params(self, rng: random.Random, instruction: int) -> bytes:
        """Plausible (and now and then absurd) parameters for `instruction`."""
        if instruction == READ:
            return bytes([self._address(rng), self._length(rng)])
        if instruction in (WRITE, REG_WRITE):
            address, size = (
                rng.choice(ITEMS)
                if rng.random() < 0.8
                else (self._address(rng), rng.randrange(0, 8))
            )
            if rng.random() < 0.1 and size > 1:
                size -= 1  # a partial multi-byte register
            return bytes([address]) + self._value(rng, size)
        if instruction == SYNC_WRITE:
            address, size = rng.choice(ITEMS)
            rows = b"".join(
                bytes([self._id(rng)]) + self._value(rng, size) for _ in range(rng.randrange(0, 6))
            )
            return bytes([address, size]) + rows
        if instruction == BULK_READ:
            rows = b"".join(
                bytes([self._length(rng), self._id(rng), self._address(rng)])
                for _ in range(rng.randrange(0, 6))
            )
            return (b"\x00" if rng.random() < 0.9 else bytes([rng.randrange(256)])) + rows
        return b"" if rng.random() < 0.9 else self._value(rng, rng.randrange(1, 6))

    def valid(self, rng: random.Random) -> bytes:
        """One well-formed packet with field-aware parameters."""
        instruction = (
            rng.randrange(256) if rng.random() < 0.05 else rng.choices(INSTRUCTIONS, _WEIGHTS)[0]
        )
        return packet(self._id(rng), instruction, self.params(rng, instruction)[: MAX_LEN - 2])

    def random_bytes(self, rng: random.Random) -> bytes:
        size = rng.randrange(0, 64) if rng.random() < 0.9 else rng.randrange(64, 600)
        data = bytearray(rng.randrange(256) for _ in range(size))
        if data and rng.random() < 0.5:
            spot = rng.randrange(len(data))
            data[spot:spot] = HEADER[: rng.randrange(1, 3)]
        return bytes(data)

    def bit_flip(self, rng: random.Random) -> bytes:
        data = bytearray(self.valid(rng))
        for _ in range(rng.randrange(1, 4)):
            data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
        return bytes(data)

    def truncated(self, rng: random.Random) -> bytes:
        data = self.valid(rng)
        return data[: rng.randrange(len(data))]

    def wrong_length(self, rng: random.Random) -> bytes:
        data = bytearray(self.valid(rng))
        length = rng.choice(
            (0, 1, 247, 255, rng.randrange(256), max(0, data[3] - 1), data[3] + 1, data[3] + 3)
        )
        data[3] = length & 0xFF
        if rng.random() < 0.6:  # a consistent checksum for the new LEN
            body = bytes(data[2 : 2 + max(0, data[3] + 1)])
            body += bytes(rng.randrange(256) for _ in range(max(0, data[3] + 1) - len(body)))
            return HEADER + body + bytes([checksum(body)])
        return bytes(data)

    def bad_checksum(self, rng: random.Random) -> bytes:
        data = bytearray(self.valid(rng))
        data[-1] ^= rng.randrange(1, 256)
        return bytes(data)

    def splice(self, rng: random.Random) -> bytes:
        first, second = self.valid(rng), self.valid(rng)
        pick = rng.random()
        if pick < 0.4:
            return first[: rng.randrange(len(first))] + second[rng.randrange(len(second)) :]
        if pick < 0.7:
            spot = rng.randrange(len(first))
            return first[:spot] + second + first[spot:]
        return first[:4] + second[4:]

    def stream(self, rng: random.Random) -> bytes:
        """Several packets back to back, with noise between some of them."""
        parts = []
        for _ in range(rng.randrange(2, 6)):
            parts.append(self.valid(rng))
            if rng.random() < 0.3:
                parts.append(self.random_bytes(rng)[:8])
        return b"".join(parts)

    def protocol2(self, rng: random.Random) -> bytes:
        """Protocol 2.0 packets (ping, read, write) for the same IDs, alone or between P1 ones."""
        instruction = rng.choice((1, 2, 3))
        params = b"" if instruction == 1 else bytes([rng.randrange(256), 0, 4, 0])
        p2 = packet2(self._id(rng), instruction, params)
        return p2 if rng.random() < 0.5 else self.valid(rng) + p2 + self.valid(rng)


def may_leave_partial(data: bytes) -> bool:
    """Whether a receiver could still be holding part of a packet after `data`."""
    return HEADER in data or data.endswith(b"\xff")
