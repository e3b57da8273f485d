"""Control-table facts as data: one `Register` per item, one `ServoTable` per servo model."""

from __future__ import annotations

import difflib
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Literal

from snakebot.errors import SnakebotError
from snakebot.servo.ticks import X_SERIES_TICKS, TickModel

ACCESS_MODES = ("R", "RW")


class UnknownRegisterError(SnakebotError, KeyError):
    """A register name or key is not in a model's control table; the message lists close names."""

    def __init__(self, model: str, key: str, candidates: list[str]) -> None:
        self.model = model
        self.key = key
        close = difflib.get_close_matches(key, candidates, n=4, cutoff=0.5)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        self.message = f"{model} has no register {key!r}{hint}"
        super().__init__(self.message)

    def __str__(self) -> str:
        return self.message


class UnknownModelError(SnakebotError, LookupError):
    """A servo model name or model number has no control-table data."""


class RegisterValueError(SnakebotError, ValueError):
    """A value does not fit the register size it is encoded into."""


def register_key(name: str) -> str:
    """Return the snake_case key of an SDK item name ("Goal Position" -> "goal_position")."""
    return re.sub(r"[^0-9a-z]+", "_", name.lower()).strip("_")


def decode_signed(raw: int, size: int) -> int:
    """Interpret the unsigned `raw` value of `size` bytes as two's complement."""
    bits = 8 * size
    raw &= (1 << bits) - 1
    return raw - (1 << bits) if raw >> (bits - 1) else raw


def decode_magnitude(raw: int, sign_bit: int) -> int:
    """Read `raw` as sign-magnitude: bit `sign_bit` the sign (set = negative), below it the size.

    Dynamixel Protocol 1.0 Present Speed/Load use bit 10 (e-Manual AX-12A "Present Load"); Feetech
    registers use bit 15 or 11. Bits above `sign_bit` are ignored.
    """
    magnitude = raw & ((1 << sign_bit) - 1)
    return -magnitude if (raw >> sign_bit) & 1 else magnitude


def encode_magnitude(value: int, sign_bit: int) -> int:
    """The sign-magnitude raw value of `value` (bit `sign_bit` set when negative).

    Raises RegisterValueError when |value| needs more than `sign_bit` bits.
    """
    if abs(value) >= 1 << sign_bit:
        raise RegisterValueError(
            f"{value} does not fit in {sign_bit} magnitude bits (sign in bit {sign_bit})"
        )
    return -value | (1 << sign_bit) if value < 0 else value


def encode_value(value: int, size: int) -> bytes:
    """Encode `value` little-endian in `size` bytes, negatives as two's complement.

    Raises RegisterValueError when the value fits neither the signed nor the unsigned range.
    """
    bits = 8 * size
    if not -(1 << (bits - 1)) <= value < (1 << bits):
        raise RegisterValueError(f"{value} does not fit in {size} byte(s)")
    return (value & ((1 << bits) - 1)).to_bytes(size, "little")


@dataclass(frozen=True)
class Register:
    """One control-table item: where it lives, who may write it, its range and its SI unit.

    `signed` means two's complement; `sign_bit` (when not None) means sign-magnitude with that
    bit as the sign (P1 Present Speed/Load: bit 10), and then `signed` is False, so a raw reader
    sees the unsigned bits and :meth:`value_of` turns them into the value. `minimum`/`maximum`/
    `default` are values (negative where the register can be), not raw bit patterns.
    `byteorder` is how the item's bytes go on the wire: "little" (Dynamixel, Feetech STS) or
    "big" (Feetech SCS, whose END register reads 1); `value_of`/`raw_of` work on the integer and
    do not depend on it, `decode`/`encode` on bytes do.
    """

    name: str
    key: str
    address: int
    size: int
    access: str
    eeprom: bool
    minimum: int
    maximum: int
    default: int
    unit: str
    scale: float
    signed: bool
    sign_bit: int | None = None
    byteorder: str = "little"

    @property
    def sign(self) -> str:
        """How a negative value is encoded: "unsigned" (never), "twos" or "magnitude"."""
        if self.sign_bit is not None:
            return "magnitude"
        return "twos" if self.signed else "unsigned"

    def value_of(self, raw: int) -> int:
        """The value of the unsigned integer `raw` (the item's bits) read from this item."""
        raw &= (1 << (8 * self.size)) - 1
        if self.sign_bit is not None:
            return decode_magnitude(raw, self.sign_bit)
        return decode_signed(raw, self.size) if self.signed else raw

    def raw_of(self, value: int) -> int:
        """The unsigned integer (the item's bits) that encodes `value`.

        Raises RegisterValueError when the value does not fit the item.
        """
        if self.sign_bit is not None:
            return encode_magnitude(value, self.sign_bit)
        return int.from_bytes(encode_value(value, self.size), "little")

    def decode(self, data: bytes | bytearray) -> int:
        """Decode the item's bytes (in its byte order) into its value (two's complement or
        sign-magnitude where the item is)."""
        order: Literal["little", "big"] = "big" if self.byteorder == "big" else "little"
        return self.value_of(int.from_bytes(bytes(data[: self.size]), order))

    def encode(self, value: int) -> bytes:
        """Encode a value into the item's bytes, in its byte order (RegisterValueError if too
        big)."""
        order: Literal["little", "big"] = "big" if self.byteorder == "big" else "little"
        return self.raw_of(value).to_bytes(self.size, order)

    def to_si(self, value: int) -> float:
        """Convert a register value into SI (`unit`), e.g. ticks to radians."""
        return value * self.scale

    def from_si(self, value: float) -> int:
        """Convert an SI value into the nearest register value (not clamped to the range)."""
        return round(value / self.scale)

    @property
    def writable(self) -> bool:
        """Whether the item accepts writes at all (EEPROM items only with torque off)."""
        return self.access == "RW"


@dataclass(frozen=True)
class ServoSpecs:
    """Model facts beyond the register list that a driver or an emulator needs.

    `baud_rates` maps the Baud Rate register value to bit/s; `indirect_banks` holds
    (first Indirect Address, first Indirect Data, count) per bank; `ticks` is how the position
    registers count; `fast_sync_read`/`bulk_read` whether the model's firmware has those group
    reads (the family decides whether its protocol has them at all); `gains` how its position
    loop is set: "pid" (Position P/D Gain registers) or "compliance" (AX compliance slope);
    `axes` how many motors share one case and its one communication module (2 on a 2XL430),
    each with its own ID and control table; `position_mode` the Operating Mode value of
    position control (3 on Dynamixel, 0 on Feetech STS).
    """

    firmware_version: int = 46
    eeprom_end: int = 64
    ticks: TickModel = X_SERIES_TICKS
    fast_sync_read: bool = True
    bulk_read: bool = True
    gains: str = "pid"
    operating_modes: tuple[int, ...] = (3,)
    baud_rates: Mapping[int, int] = field(default_factory=lambda: MappingProxyType({}))
    indirect_banks: tuple[tuple[int, int, int], ...] = ()
    nominal_voltage_v: float = 12.0
    no_load_speed_rad_s: float = 5.0
    stall_torque_nm: float = 1.0
    stall_current_a: float = 1.0
    axes: int = 1
    position_mode: int = 3

    @property
    def resolution(self) -> int:
        """Position ticks over the model's range of travel (4096, or 1024 on an AX-12A)."""
        return self.ticks.count


@dataclass(frozen=True, eq=False)
class ServoTable:
    """The control table of one servo model; look items up by key, SDK name or address.

    Compared and hashed by identity (`table_for_model` returns one instance per model), so a
    table can key a dict or a cache.
    """

    model: str
    model_number: int
    protocol: float
    registers: Mapping[str, Register]
    specs: ServoSpecs = field(default_factory=ServoSpecs)
    family: str = "dynamixel"
    protocols: tuple[float, ...] = ()
    _by_address: Mapping[int, Register] = field(init=False, repr=False, compare=False)
    _by_name: Mapping[str, Register] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        by_address: dict[int, Register] = {}
        by_name: dict[str, Register] = {}
        for register in self.registers.values():
            by_address.setdefault(register.address, register)
            by_name.setdefault(register_key(register.name), register)
        object.__setattr__(self, "_by_name", MappingProxyType(by_name))
        object.__setattr__(self, "registers", MappingProxyType(dict(self.registers)))
        if not self.protocols:
            object.__setattr__(self, "protocols", (float(self.protocol),))
        object.__setattr__(self, "_by_address", MappingProxyType(by_address))

    def _find(self, key: str) -> Register | None:
        found = self.registers.get(key)  # a key as such: no normalising (hot in the emulator)
        if found is not None:
            return found
        normal = register_key(key)
        return self.registers.get(normal) or self._by_name.get(normal)

    def __getitem__(self, key: str) -> Register:
        """Return the register for a key ("goal_position", "min_position_limit") or its
        datasheet name ("Goal Position", "CW Angle Limit")."""
        register = self._find(key)
        if register is None:
            raise UnknownRegisterError(self.model, key, list(self.registers))
        return register

    def __contains__(self, key: object) -> bool:
        return isinstance(key, str) and self._find(key) is not None

    def by_address(self, address: int) -> Register | None:
        """Return the register starting at `address` (the first listed, for aliases), or None."""
        return self._by_address.get(address)

    @property
    def size(self) -> int:
        """Bytes of control-table memory the model needs, up to its last item."""
        ends = [r.address + r.size for r in self.registers.values()]
        ends += [data + count for _, data, count in self.specs.indirect_banks]
        return max(ends)

    @property
    def baud_rates(self) -> Mapping[int, int]:
        """Baud Rate register value -> bit/s."""
        return self.specs.baud_rates

    def baud_index(self, baud: int) -> int:
        """Return the Baud Rate register value for `baud` bit/s (RegisterValueError if none)."""
        for index, rate in self.specs.baud_rates.items():
            if rate == baud:
                return index
        rates = ", ".join(str(r) for r in self.specs.baud_rates.values())
        raise RegisterValueError(f"{self.model} does not support {baud} bit/s; supported: {rates}")
