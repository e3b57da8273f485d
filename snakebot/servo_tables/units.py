"""Setting names with unit suffixes: ``return_delay_time_us = 0`` means 0 µs, converted to ticks.

A settings key is a control-table key (``snakebot.servo_tables``), optionally followed by a unit
suffix from :data:`UNITS`; without a suffix the value is the raw register value. Angles of the
Min/Max Position Limit are measured from the centre tick (2048 on a 4096-tick servo), the same
zero the joint angles use; Homing Offset angles are plain offsets.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from snakebot.servo.ticks import centre_tick
from snakebot.servo_tables import Register, ServoTable

CENTRED_KEYS = frozenset({"min_position_limit", "max_position_limit"})


@dataclass(frozen=True)
class Unit:
    """A unit a setting may be written in: ``si_per_unit`` SI (``si_unit``) per user unit."""

    suffix: str
    symbol: str
    si_unit: str
    si_per_unit: float


UNITS: dict[str, Unit] = {
    u.suffix: u
    for u in (
        Unit("us", "us", "s", 1e-6),
        Unit("ms", "ms", "s", 1e-3),
        Unit("s", "s", "s", 1.0),
        Unit("deg", "deg", "rad", math.pi / 180.0),
        Unit("rad", "rad", "rad", 1.0),
        Unit("rpm", "rpm", "rad/s", 2.0 * math.pi / 60.0),
        Unit("deg_s", "deg/s", "rad/s", math.pi / 180.0),
        Unit("rad_s", "rad/s", "rad/s", 1.0),
        Unit("v", "V", "V", 1.0),
        Unit("c", "degC", "degC", 1.0),
        Unit("pct", "%", "%", 1.0),
        Unit("a", "A", "A", 1.0),
        Unit("ma", "mA", "A", 1e-3),
    )
}


class UnitError(ValueError):
    """A settings key names no register, or a unit that does not fit the register."""


def parse_key(table: ServoTable, key: str) -> tuple[Register, Unit | None]:
    """The register and unit a settings key names (``bus_watchdog_ms`` -> Bus Watchdog, ms)."""
    if key in table.registers:
        return table.registers[key], None
    for suffix in sorted(UNITS, key=len, reverse=True):
        base = key.removesuffix(f"_{suffix}")
        if base != key and base in table.registers:
            register, unit = table.registers[base], UNITS[suffix]
            if register.unit != unit.si_unit:
                have = f"in {register.unit}" if register.unit else "a raw number (no unit)"
                raise UnitError(f"{table.model} {base} is {have}; _{suffix} does not fit")
            return register, unit
    suffixes = ", ".join(f"_{s}" for s in UNITS)
    try:
        table[key]
    except KeyError as exc:
        raise UnitError(f"{exc} (optionally followed by a unit: {suffixes})") from None
    raise UnitError(f"{key!r} is an alias; use the register key {table[key].key!r}")


def _centre(register: Register, table: ServoTable) -> int:
    return centre_tick(table.specs.ticks) if register.key in CENTRED_KEYS else 0


def to_raw(register: Register, unit: Unit | None, value: float, table: ServoTable) -> int:
    """A value in ``unit`` (raw if None) as the nearest register value (not range-checked)."""
    if unit is None:
        if not float(value).is_integer():
            raise UnitError(f"{register.key} takes a whole raw register value, got {value}")
        return int(value)
    si = value * unit.si_per_unit
    if not math.isfinite(si / register.scale):  # 1e307 rad: no register holds it
        raise UnitError(f"{register.key}: {value} {unit.symbol} is far outside the register")
    return _centre(register, table) + register.from_si(si)


def from_raw(register: Register, unit: Unit | None, raw: int, table: ServoTable) -> float:
    """A register value in ``unit`` (the raw value if None)."""
    if unit is None:
        return float(raw)
    return register.to_si(raw - _centre(register, table)) / unit.si_per_unit


def display(register: Register, unit: Unit | None, raw: int, table: ServoTable) -> tuple[str, str]:
    """(value, unit label) for a table: ``("500", "us")``, ``("1000000", "bit/s")``."""
    if register.key == "baud_rate":
        return str(table.baud_rates.get(raw, f"index {raw}")), "bit/s"
    if unit is None:
        return str(raw), ""
    value = round(from_raw(register, unit, raw, table), 3)
    text = f"{value:.3f}".rstrip("0").rstrip(".")
    return ("0" if text in ("-0", "") else text), unit.symbol
