"""One servo's control-table memory: the bytes, the item layout and the static write rules."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace
from typing import Literal

from snakebot.emulation.protocol import StatusError
from snakebot.servo_tables import Register, ServoTable


@dataclass(frozen=True)
class WritePlan:
    """What a write would change: `error` (0 = allowed so far), item values, bytes to store."""

    error: int
    values: dict[str, int]
    items: tuple[Register, ...]
    stores: tuple[tuple[int, int], ...]


def _indirect_items(table: ServoTable) -> list[Register]:
    """Registers for every Indirect Address/Data entry (the table lists only entry 1)."""
    if "indirect_address_1" not in table or "indirect_data_1" not in table:
        return []
    first_address, first_data = table["indirect_address_1"], table["indirect_data_1"]
    items: list[Register] = []
    number = 0
    for address_start, data_start, count in table.specs.indirect_banks:
        for k in range(count):
            number += 1
            items.append(
                replace(
                    first_address,
                    name=f"Indirect Address {number}",
                    key=f"indirect_address_{number}",
                    address=address_start + 2 * k,
                    default=data_start + k,
                )
            )
            items.append(
                replace(
                    first_data,
                    name=f"Indirect Data {number}",
                    key=f"indirect_data_{number}",
                    address=data_start + k,
                )
            )
    return items


ByteOrder = Literal["little", "big"]


def byte_order(table: ServoTable) -> ByteOrder:
    """How the model stores two-byte items: the model data's byte order (big-endian only on a
    Feetech SCS, whose END register (2) reads 1; wiki memory-scscl.md)."""
    orders = {register.byteorder for register in table.registers.values()}
    return "big" if orders == {"big"} else "little"


@dataclass(frozen=True)
class _Layout:
    """Where every item of one model lives, and the factory-default image (built once per model)."""

    items: dict[int, Register]
    by_key: dict[str, Register]
    owner: tuple[int, ...]
    indirect: dict[int, int]
    defaults: bytes
    order: ByteOrder
    # key: (start, end, signed, writable, the register itself where it is sign-magnitude)
    spans: dict[str, tuple[int, int, bool, bool, Register | None]]


_layouts: dict[ServoTable, _Layout] = {}


def _layout(table: ServoTable) -> _Layout:
    cached = _layouts.get(table)
    if cached is not None:
        return cached
    items: dict[int, Register] = {}
    for register in [*table.registers.values(), *_indirect_items(table)]:
        items.setdefault(register.address, register)
    by_key = {register.key: register for register in items.values()}
    by_key.update(table.registers)
    owner = [-1] * table.size
    image = bytearray(table.size)
    order = byte_order(table)
    for address, register in items.items():
        owner[address : address + register.size] = [address] * register.size
        raw = register.raw_of(register.default)
        image[address : address + register.size] = raw.to_bytes(register.size, order)
    indirect = {
        register.address: by_key["indirect_address_" + register.key.rsplit("_", 1)[1]].address
        for register in items.values()
        if register.key.startswith("indirect_data_")
    }
    spans = {
        key: (
            r.address,
            r.address + r.size,
            r.signed,
            r.access == "RW",
            r if r.sign_bit is not None else None,
        )
        for key, r in by_key.items()
    }
    layout = _Layout(items, by_key, tuple(owner), indirect, bytes(image), order, spans)
    _layouts[table] = layout
    return layout


class ControlTableMemory:
    """The bytes of a control table with its layout; no servo semantics (torque lock, limits)."""

    def __init__(self, table: ServoTable) -> None:
        self.table = table
        layout = _layout(table)
        self._layout = layout
        self.items, self.by_key = layout.items, layout.by_key
        self._owner, self._indirect = layout.owner, layout.indirect
        self._spans = layout.spans
        self.order: ByteOrder = layout.order
        self._indirect_span = (min(self._indirect, default=0), max(self._indirect, default=0))
        self.data = bytearray(layout.defaults)
        self.version = 0

    # `version` counts changes of writable items so that the motor command can be cached.
    def get(self, key: str) -> int:
        """Decode the item `key` from memory (signed where the item is)."""
        start, end, signed, _, magnitude = self._spans[key]  # per packet per servo: kept lean
        if magnitude is not None:
            return magnitude.value_of(int.from_bytes(self.data[start:end], self.order))
        return int.from_bytes(self.data[start:end], self.order, signed=signed)

    def set(self, key: str, value: int) -> None:
        """Store `value` in item `key` without any rule; values are wrapped to the item's size."""
        start, end, _, writable, magnitude = self._spans[key]
        if writable:
            self.version += 1
        size = end - start
        if magnitude is not None and magnitude.sign_bit is not None:
            # Sign-magnitude (P1 Present Speed/Load): clipped to what the magnitude bits hold.
            limit = (1 << magnitude.sign_bit) - 1
            value = magnitude.raw_of(max(-limit, min(limit, value)))
        self.data[start:end] = (value & ((1 << (8 * size)) - 1)).to_bytes(size, self.order)

    def has(self, key: str) -> bool:
        """Whether the model has item `key`."""
        return key in self.by_key

    def load_defaults(self, keep: Iterable[str] = ()) -> None:
        """Reset every item to its factory default, except the keys in `keep`."""
        kept = [self.by_key[key] for key in keep]
        saved = [bytes(self.data[r.address : r.address + r.size]) for r in kept]
        self.data[:] = self._layout.defaults
        for register, value in zip(kept, saved, strict=True):
            self.data[register.address : register.address + register.size] = value
        self.version += 1

    def _target(self, address: int) -> int:
        """The address a byte access lands on: indirect data bytes follow their indirect address."""
        pointer = self._indirect.get(address)
        if pointer is None:
            return address
        target = int.from_bytes(self.data[pointer : pointer + 2], "little")
        return target if 0 <= target < len(self.data) else address

    def read(self, address: int, length: int) -> tuple[int, bytes]:
        """Return (error, bytes) for a read; undefined gaps read as stored (zero)."""
        if length <= 0:
            return StatusError.DATA_LENGTH, b""
        if address < 0 or address + length > len(self.data):
            return StatusError.ACCESS, b""
        end = address + length
        if not self._indirect or end <= self._indirect_span[0] or address > self._indirect_span[1]:
            return 0, bytes(self.data[address:end])
        return 0, bytes(self.data[self._target(a)] for a in range(address, end))

    def plan_write(self, address: int, payload: bytes) -> WritePlan:
        """Check a write against layout, access, length and static range; nothing is stored."""
        end = address + len(payload)
        if not payload:
            return WritePlan(StatusError.DATA_LENGTH, {}, (), ())
        if address < 0 or end > len(self.data) or address not in self.items:
            return WritePlan(StatusError.ACCESS, {}, (), ())
        last = self._owner[end - 1]
        if last >= 0 and last + self.items[last].size > end:
            return WritePlan(StatusError.DATA_LENGTH, {}, (), ())
        shadow = bytearray(self.data)
        stores: list[tuple[int, int]] = []
        touched: dict[int, Register] = {}
        for offset, byte in enumerate(payload):
            target = self._target(address + offset)
            owner = self._owner[target]
            if owner < 0:
                continue
            touched[owner] = self.items[owner]
            shadow[target] = byte
            stores.append((target, byte))
        values: dict[str, int] = {}
        for start, register in touched.items():
            if register.access != "RW":
                return WritePlan(StatusError.ACCESS, {}, (), ())
            raw = int.from_bytes(shadow[start : start + register.size], self.order)
            value = register.value_of(raw)
            if not register.minimum <= value <= register.maximum:
                return WritePlan(StatusError.DATA_RANGE, {}, (), ())
            values[register.key] = value
        return WritePlan(0, values, tuple(touched.values()), tuple(stores))

    def store(self, plan: WritePlan) -> None:
        """Apply a write plan's bytes."""
        self.version += 1
        for target, byte in plan.stores:
            self.data[target] = byte
