"""Contiguous register blocks: which bytes one read or write covers and how to decode them.

A block is resolved once from register names (via ``snakebot.servo_tables``) and then decodes raw
bytes either into ``{key: int}`` per servo or, for the control loop, into one numpy array per key.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from snakebot.servo_tables import Register, RegisterValueError, ServoTable
from snakebot.servo_tables.table import decode_magnitude


@dataclass(frozen=True)
class Field:
    """One register inside a block: its key, byte offset from the block start, size and sign
    (``signed``: two's complement; ``sign_bit``: sign-magnitude with that bit the sign, as
    Protocol 1.0's Present Speed/Load, bit 10), and its byte order ("big" on Feetech SCS)."""

    key: str
    offset: int
    size: int
    signed: bool
    sign_bit: int | None = None
    byteorder: str = "little"

    def decode(self, data: bytes) -> int:
        """The field's value from the block's bytes."""
        order: Literal["little", "big"] = "big" if self.byteorder == "big" else "little"
        raw = int.from_bytes(data[self.offset : self.offset + self.size], order, signed=self.signed)
        return raw if self.sign_bit is None else decode_magnitude(raw, self.sign_bit)


@dataclass(frozen=True)
class Block:
    """``size`` bytes from ``address`` holding ``fields``; gaps between fields are read, ignored."""

    address: int
    size: int
    fields: tuple[Field, ...]

    @property
    def keys(self) -> tuple[str, ...]:
        """Register keys in address order."""
        return tuple(f.key for f in self.fields)

    def decode(self, data: bytes | bytearray | Sequence[int]) -> dict[str, int]:
        """``{key: value}`` from one servo's block bytes; ValueError if the length is wrong."""
        raw = bytes(data)
        if len(raw) != self.size:
            raise ValueError(
                f"expected {self.size} bytes from address {self.address}, got {len(raw)}"
            )
        return {f.key: f.decode(raw) for f in self.fields}


def resolve_block(table: ServoTable, keys: str | Sequence[str]) -> Block:
    """The smallest contiguous block covering the named registers (UnknownRegisterError if unknown).

    ``keys`` is one register name or several; e.g. ``("present_load", "present_velocity",
    "present_position")`` gives addresses 126..135 on an XL430.
    """
    names = [keys] if isinstance(keys, str) else list(keys)
    if not names:
        raise ValueError("a register block needs at least one register name")
    registers: dict[str, Register] = {}
    for name in names:
        register = table[name]
        registers[register.key] = register
    ordered = sorted(registers.values(), key=lambda r: r.address)
    start = ordered[0].address
    end = max(r.address + r.size for r in ordered)
    fields = tuple(
        Field(r.key, r.address - start, r.size, r.signed, r.sign_bit, r.byteorder) for r in ordered
    )
    return Block(start, end - start, fields)


def encode_rows(
    block: Block, table: ServoTable, values: Mapping[int, int | Sequence[int]]
) -> list[tuple[int, bytes]]:
    """Validate and encode ``{id: value or values in field order}`` into ``(id, block bytes)``.

    Each value must lie within its register's range (RegisterValueError otherwise) and the
    registers must be writable and fill the block without gaps.
    """
    if sum(f.size for f in block.fields) != block.size:
        raise ValueError(f"registers {', '.join(block.keys)} are not contiguous; write them apart")
    rows = []
    for dxl_id, value in values.items():
        items = [value] if isinstance(value, int | np.integer) else list(value)
        if len(items) != len(block.fields):
            raise ValueError(f"servo {dxl_id}: {len(items)} values for registers {block.keys}")
        data = b"".join(
            encode_checked(table[f.key], int(v)) for f, v in zip(block.fields, items, strict=True)
        )
        rows.append((dxl_id, data))
    return rows


def encode_checked(register: Register, value: int) -> bytes:
    """A register value's bytes, after checking access and the register's range."""
    if not register.writable:
        raise RegisterValueError(f"register {register.key} ({register.address}) is read-only")
    if not register.minimum <= value <= register.maximum:
        raise RegisterValueError(
            f"{register.key} = {value} is outside {register.minimum}..{register.maximum}"
        )
    return register.encode(value)
