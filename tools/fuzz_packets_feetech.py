"""Feetech FT-SCS fuzz inputs for the emulated bus (STS and SCS servos).

Built from Feetech's protocol page (wiki protocol/ft-scs.md; servo-families.md §1), not from the
emulator's codec: the framing (and its checksum) is Protocol 1.0's, so the families, the packet
builder and the reference reading of `fuzz_packets1` serve; what differs is the instruction set
(0x06 recovery, 0x08 restart, 0x09 backup, 0x0A reset, 0x0B calibration, 0x82 sync read; no
bulk read) and the control-table items the field-aware packets aim at (memory-sts.md,
memory-scscl.md). A Feetech servo answers a damaged frame with silence: it has no Checksum bit.
"""

from __future__ import annotations

import random

from fuzz_packets1 import MAX_LEN, Inputs1, packet

PING, READ, WRITE, REG_WRITE, ACTION = 1, 2, 3, 4, 5
RECOVERY, RESTART, BACKUP, RESET, OFSCAL = 6, 8, 9, 0x0A, 0x0B
SYNC_READ, SYNC_WRITE = 0x82, 0x83
ABSENT = (0x07, 0x10, 0x55, 0x92, 0x8A, 0x93)  # Dynamixel-only codes: no reply
INSTRUCTIONS = (
    PING,
    READ,
    WRITE,
    REG_WRITE,
    ACTION,
    RECOVERY,
    RESTART,
    BACKUP,
    RESET,
    OFSCAL,
    SYNC_READ,
    SYNC_WRITE,
    *ABSENT,
)
_WEIGHTS = [
    8 if i == WRITE else 3 if i in (READ, SYNC_READ, SYNC_WRITE, REG_WRITE) else 1
    for i in INSTRUCTIONS
]
READ_ONLY = frozenset({PING, READ, SYNC_READ, BACKUP, *ABSENT})
"""Instructions that change no control-table byte (present values aside)."""

# (address, size) of STS items (memory-sts.md) and the SCS items that differ (memory-scscl.md).
ITEMS = (
    (0, 1),
    (2, 1),
    (3, 2),
    (5, 1),
    (6, 1),
    (7, 1),
    (8, 1),
    (9, 2),
    (11, 2),
    (13, 1),
    (14, 1),
    (15, 1),
    (16, 2),
    (18, 1),
    (19, 1),
    (20, 1),
    (21, 1),
    (22, 1),
    (23, 1),
    (24, 1),
    (24, 2),
    (26, 1),
    (28, 2),
    (31, 2),
    (33, 1),
    (34, 1),
    (35, 1),
    (36, 1),
    (37, 1),
    (40, 1),
    (41, 1),
    (41, 7),
    (42, 2),
    (42, 6),
    (44, 2),
    (46, 2),
    (48, 1),
    (48, 2),
    (55, 1),
    (56, 2),
    (56, 4),
    (60, 2),
    (64, 1),
    (65, 1),
    (66, 1),
    (69, 2),
)


class InputsFeetech(Inputs1):
    """Draws Feetech fuzz inputs for a chain whose servos have `ids` (the families of
    `fuzz_packets1.Inputs1`, with Feetech's instructions and items)."""

    def _address(self, rng: random.Random) -> int:
        return rng.choice(ITEMS)[0] if rng.random() < 0.8 else rng.randrange(256)

    def _value(self, rng: random.Random, size: int) -> bytes:
        if size == 1 and rng.random() < 0.1:
            return bytes([rng.choice((0, 1, 2, 128))])  # Torque Enable's values, Lock's
        value = super()._value(rng, size)
        if size == 2 and rng.random() < 0.2:
            value = bytes([value[0], value[1] | 0x80])  # a sign-magnitude negative
        return value

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
        if instruction == SYNC_READ:
            ids = bytes(self._id(rng) for _ in range(rng.randrange(0, 6)))
            return bytes([self._address(rng), self._length(rng)]) + ids
        if instruction == OFSCAL and rng.random() < 0.5:
            return self._value(rng, 2)
        return b"" if rng.random() < 0.9 else self._value(rng, rng.randrange(1, 6))

    def valid(self, rng: random.Random) -> bytes:
        """One well-formed packet with field-aware parameters."""
        instruction = (
            rng.randrange(256) if rng.random() < 0.05 else rng.choices(INSTRUCTIONS, _WEIGHTS)[0]
        )
        return packet(self._id(rng), instruction, self.params(rng, instruction)[: MAX_LEN - 2])
