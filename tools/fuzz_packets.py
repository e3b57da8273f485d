"""Fuzz inputs for the emulated Dynamixel bus, and a reference reading of what they may contain.

Inputs are built from the Protocol 2.0 documents (reference/dynamixel.md §1), not from the
emulator's codec: CRCs come from the ROBOTIS SDK's own `updateCRC`, so an emulator bug cannot
hide in the fuzzer. Each input is drawn from `random.Random(seed, index)` alone, so any single
input can be replayed (`make_input(seed, index)`).

Families: random bytes, field-aware packets (every instruction, plausible and absurd fields),
bit flips, truncations, wrong and huge LEN fields, byte-stuffing edge cases, bad CRCs, splices.
"""

from __future__ import annotations

import random
from collections.abc import Callable
from dataclasses import dataclass

from dynamixel_sdk.protocol2_packet_handler import Protocol2PacketHandler

HEADER = b"\xff\xff\xfd\x00"
BROADCAST = 0xFE
MAX_PACKET = 1024  # bytes, header to CRC (the SDK's buffers)
MAX_LEN = MAX_PACKET - 7
PING, READ, WRITE, REG_WRITE, ACTION, RESET, REBOOT, CLEAR = 1, 2, 3, 4, 5, 6, 8, 0x10
STATUS = 0x55
SYNC_READ, SYNC_WRITE, FAST_SYNC_READ = 0x82, 0x83, 0x8A
BULK_READ, BULK_WRITE, FAST_BULK_READ = 0x92, 0x93, 0x9A
INSTRUCTIONS = (
    PING,
    READ,
    WRITE,
    REG_WRITE,
    ACTION,
    RESET,
    REBOOT,
    CLEAR,
    STATUS,
    SYNC_READ,
    SYNC_WRITE,
    FAST_SYNC_READ,
    BULK_READ,
    BULK_WRITE,
    FAST_BULK_READ,
)
_INSTRUCTION_WEIGHTS = [5 if i == WRITE else 2 if i == READ else 1 for i in INSTRUCTIONS]
READ_ONLY = frozenset({PING, READ, STATUS, SYNC_READ, FAST_SYNC_READ, BULK_READ, FAST_BULK_READ})
"""Instructions that change no control-table byte (present values aside)."""

# (address, size) of X-series items, from reference/dynamixel.md §2.2; fields pick from these.
ITEMS = (
    (0, 2),
    (6, 1),
    (7, 1),
    (8, 1),
    (9, 1),
    (10, 1),
    (11, 1),
    (12, 1),
    (13, 1),
    (20, 4),
    (24, 4),
    (31, 1),
    (32, 2),
    (34, 2),
    (36, 2),
    (44, 4),
    (48, 4),
    (52, 4),
    (60, 1),
    (63, 1),
    (64, 1),
    (65, 1),
    (68, 1),
    (69, 1),
    (70, 1),
    (76, 2),
    (80, 2),
    (84, 2),
    (98, 1),
    (100, 2),
    (104, 4),
    (108, 4),
    (112, 4),
    (116, 4),
    (120, 2),
    (126, 2),
    (128, 4),
    (132, 4),
    (144, 2),
    (146, 1),
    (168, 2),
    (224, 1),
    (578, 2),
    (634, 1),
    (661, 1),
)
_sdk = Protocol2PacketHandler()


def crc16(data: bytes) -> int:
    """The SDK's CRC-16 of `data` (its `updateCRC`, independent of the emulator's)."""
    return int(_sdk.updateCRC(0, data, len(data)))


def stuff(body: bytes) -> bytes:
    """Add 0xFD after every FF FF FD (e-Manual "Processing Order of Transmission")."""
    out = bytearray()
    for byte in body:
        out.append(byte)
        if byte == 0xFD and len(out) >= 3 and out[-3] == 0xFF and out[-2] == 0xFF:
            out.append(0xFD)
    return bytes(out)


def unstuff(body: bytes) -> bytes:
    """Drop the 0xFD that follows each FF FF FD."""
    return body.replace(b"\xff\xff\xfd\xfd", b"\xff\xff\xfd")


def packet(servo_id: int, instruction: int, params: bytes, *, stuffed: bool = True) -> bytes:
    """A well-formed instruction packet (stuffed unless told otherwise)."""
    body = bytes([instruction]) + params
    body = stuff(body) if stuffed else body
    length = len(body) + 2
    head = HEADER + bytes([servo_id, length & 0xFF, (length >> 8) & 0xFF]) + body
    crc = crc16(head)
    return head + bytes([crc & 0xFF, crc >> 8])


@dataclass(frozen=True)
class Candidate:
    """A complete packet with a valid CRC found at `offset` (params unstuffed)."""

    offset: int
    servo_id: int
    instruction: int
    params: bytes


def candidates(data: bytes) -> list[Candidate]:
    """Every place in `data` where a receiver could find a valid instruction packet.

    A superset of what any receiver executes (it may skip some while inside another packet):
    header FF FF FD 00, ID 0..252 or 254, 3 <= LEN <= 1017, all bytes present, CRC valid.
    """
    found = []
    start = data.find(b"\xff\xff\xfd\x00")
    while start >= 0:
        if start + 7 <= len(data):
            servo_id = data[start + 4]
            length = data[start + 5] | data[start + 6] << 8
            end = start + 7 + length
            if (
                (servo_id <= 252 or servo_id == BROADCAST)
                and 3 <= length <= MAX_LEN
                and end <= len(data)
            ):
                crc = data[end - 2] | data[end - 1] << 8
                if crc16(data[start : end - 2]) == crc:
                    body = unstuff(data[start + 7 : end - 2])
                    found.append(Candidate(start, servo_id, body[0], body[1:]))
        start = data.find(b"\xff\xff\xfd\x00", start + 1)
    return found


class Inputs:
    """Draws fuzz inputs for a chain whose servos have `ids`."""

    def __init__(self, ids: tuple[int, ...]) -> None:
        self.ids = ids
        self._families: tuple[tuple[str, Callable[[random.Random], bytes], int], ...] = (
            ("random", self.random_bytes, 10),
            ("field", self.field_packet, 30),
            ("bitflip", self.bit_flip, 12),
            ("truncated", self.truncated, 8),
            ("length", self.wrong_length, 10),
            ("stuffing", self.stuffing_edge, 8),
            ("crc", self.bad_crc, 7),
            ("splice", self.splice, 10),
            ("stream", self.stream, 5),
        )
        self._weights = [w for _, _, w in self._families]

    def make(self, seed: int, index: int) -> tuple[str, bytes]:
        """Input number `index` of campaign `seed`: (family, bytes)."""
        rng = random.Random(seed * 1_000_003 + index)
        name, build, _ = rng.choices(self._families, self._weights)[0]
        return name, build(rng)

    # ------------------------------------------------------------------ fields
    def _id(self, rng: random.Random) -> int:
        pick = rng.random()
        if pick < 0.6:
            return rng.choice(self.ids)
        if pick < 0.85:
            return BROADCAST
        return rng.choice((0, 253, 255, rng.randrange(256)))

    def _address(self, rng: random.Random) -> int:
        if rng.random() < 0.8:
            return rng.choice(ITEMS)[0]
        return rng.choice((rng.randrange(700), rng.randrange(65536), 0xFFFF))

    def _length(self, rng: random.Random) -> int:
        pick = rng.random()
        if pick < 0.7:
            return rng.choice((1, 2, 4, 10, rng.randrange(1, 16)))
        if pick < 0.9:
            return rng.randrange(0, 1100)
        return rng.choice((0, 1013, 1014, 65535, rng.randrange(65536)))

    def _value(self, rng: random.Random, size: int) -> bytes:
        pick = rng.random()
        if pick < 0.3:
            return bytes(rng.randrange(256) for _ in range(size))
        if pick < 0.55:  # modes, baud indices, flags, small limits
            value = rng.randrange(0, 20)
        elif pick < 0.75:  # positions, gains
            value = rng.randrange(0, 4096)
        elif pick < 0.9:  # beyond limits, and small negatives (two's complement)
            value = rng.choice((rng.randrange(4096, 70000), -rng.randrange(1, 5000)))
        else:
            return bytes([rng.choice((0, 1, 0x7F, 0x80, 0xFD, 0xFF))] * size)
        return (value % (1 << (8 * size))).to_bytes(size, "little")

    def _u16(self, value: int) -> bytes:
        return (value & 0xFFFF).to_bytes(2, "little")

    def params(self, rng: random.Random, instruction: int) -> bytes:
        """Plausible (and now and then absurd) parameters for `instruction`."""
        if instruction in (READ,):
            return self._u16(self._address(rng)) + self._u16(self._length(rng))
        if instruction in (WRITE, REG_WRITE):
            address, size = (
                rng.choice(ITEMS)
                if rng.random() < 0.8
                else (self._address(rng), rng.randrange(0, 12))
            )
            return self._u16(address) + self._value(rng, size)
        if instruction == RESET:
            return bytes([rng.choice((0x01, 0x02, 0xFF, rng.randrange(256)))])
        if instruction == CLEAR:
            return b"\x01\x44\x58\x4c\x22" if rng.random() < 0.5 else self._value(rng, 5)
        if instruction in (SYNC_READ, FAST_SYNC_READ):
            ids = bytes(self._id(rng) for _ in range(rng.randrange(0, 12)))
            length = self._length(rng)
            if rng.random() < 0.05:  # a long chain: IDs 1..n, as a big robot would ask
                ids = bytes(range(1, rng.randrange(2, 120)))
                length = rng.randrange(1, 1100)
            return self._u16(self._address(rng)) + self._u16(length) + ids
        if instruction == SYNC_WRITE:
            address, size = rng.choice(ITEMS)
            rows = b"".join(
                bytes([self._id(rng)]) + self._value(rng, size) for _ in range(rng.randrange(0, 6))
            )
            return self._u16(address) + self._u16(size) + rows
        if instruction in (BULK_READ, FAST_BULK_READ):
            return b"".join(
                bytes([self._id(rng)])
                + self._u16(self._address(rng))
                + self._u16(self._length(rng))
                for _ in range(rng.randrange(0, 6))
            )
        if instruction == BULK_WRITE:
            rows = b""
            for _ in range(rng.randrange(0, 5)):
                address, size = rng.choice(ITEMS)
                rows += bytes([self._id(rng)]) + self._u16(address) + self._u16(size)
                rows += self._value(rng, size)
            return rows
        return b"" if rng.random() < 0.9 else self._value(rng, rng.randrange(1, 6))

    def _instruction(self, rng: random.Random) -> int:
        if rng.random() < 0.05:
            return rng.randrange(256)
        return rng.choices(INSTRUCTIONS, _INSTRUCTION_WEIGHTS)[0]

    def valid(self, rng: random.Random) -> bytes:
        """One well-formed packet with field-aware parameters."""
        instruction = self._instruction(rng)
        return packet(self._id(rng), instruction, self.params(rng, instruction))

    # ------------------------------------------------------------------ families
    def random_bytes(self, rng: random.Random) -> bytes:
        size = rng.randrange(0, 64) if rng.random() < 0.9 else rng.randrange(64, 2100)
        data = bytearray(rng.randrange(256) for _ in range(size))
        if data and rng.random() < 0.5:  # a header somewhere makes the parser work
            spot = rng.randrange(len(data))
            data[spot:spot] = HEADER[: rng.randrange(1, 5)]
        return bytes(data)

    def field_packet(self, rng: random.Random) -> bytes:
        return self.valid(rng)

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
        true = data[5] | data[6] << 8
        pick = rng.random()
        if pick < 0.4:
            length = max(0, true + rng.choice((-3, -2, -1, 1, 2, 5)))
        elif pick < 0.7:
            length = rng.choice((0, 1, 2, MAX_LEN, MAX_LEN + 1, 0x7FFF, 0xFFFF))
        else:
            length = rng.randrange(65536)
        data[5:7] = self._u16(length)
        if rng.random() < 0.6 and length <= 2 * MAX_PACKET:  # consistent CRC for the new LEN
            body = bytes(data[7 : 7 + max(0, length - 2)])
            body += bytes(rng.randrange(256) for _ in range(max(0, length - 2) - len(body)))
            head = bytes(data[:7]) + body
            crc = crc16(head)
            return head + bytes([crc & 0xFF, crc >> 8])
        return bytes(data)

    def stuffing_edge(self, rng: random.Random) -> bytes:
        instruction = rng.choice((WRITE, REG_WRITE, SYNC_WRITE, BULK_WRITE, READ, PING))
        params = bytearray(self.params(rng, instruction))
        pattern = rng.choice(
            (
                b"\xff\xff\xfd",
                b"\xff\xff\xfd\xfd",
                b"\xff\xff",
                b"\xff",
                b"\xff\xff\xfd\x00",
                b"\xfd\xfd\xfd",
            )
        )
        spot = rng.randrange(len(params) + 1)
        params[spot:spot] = pattern
        return packet(self._id(rng), instruction, bytes(params), stuffed=rng.random() < 0.6)

    def bad_crc(self, rng: random.Random) -> bytes:
        data = bytearray(self.valid(rng))
        data[-1 - rng.randrange(2)] ^= rng.randrange(1, 256)
        return bytes(data)

    def splice(self, rng: random.Random) -> bytes:
        first, second = self.valid(rng), self.valid(rng)
        pick = rng.random()
        if pick < 0.4:
            return first[: rng.randrange(len(first))] + second[rng.randrange(len(second)) :]
        if pick < 0.7:
            spot = rng.randrange(len(first))
            return first[:spot] + second + first[spot:]
        return first[:7] + second[7:]

    def stream(self, rng: random.Random) -> bytes:
        """Several packets back to back, with noise between some of them."""
        parts = []
        for _ in range(rng.randrange(2, 6)):
            parts.append(self.valid(rng))
            if rng.random() < 0.3:
                parts.append(self.random_bytes(rng)[:8])
        return b"".join(parts)


def may_leave_partial(data: bytes) -> bool:
    """Whether a receiver could still be holding part of a packet after `data`."""
    return b"\xff\xff\xfd" in data or data.endswith(b"\xff")
