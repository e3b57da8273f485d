"""Servo families: each protocol one class, each model data (see :mod:`snakebot.families.base`).

``family_for(table, protocol)`` is how the backend, setup, scan and the emulator learn what a
servo can do; ``FAMILIES`` lists every family snakebot speaks.
"""

from __future__ import annotations

from snakebot.errors import ConfigError
from snakebot.families.base import READ_METHODS, Capabilities, EepromLock, ServoFamily, WireCost
from snakebot.families.dynamixel import DynamixelProtocol1, DynamixelProtocol2
from snakebot.families.feetech import FeetechSCS, FeetechSTS
from snakebot.servo_tables import ServoTable

FAMILIES: tuple[ServoFamily, ...] = (
    DynamixelProtocol2(),
    DynamixelProtocol1(),
    FeetechSTS(),
    FeetechSCS(),
)


def family_named(name: str) -> ServoFamily:
    """The family called ``name`` ("dynamixel-p1", "feetech-sts"); ConfigError listing the
    names otherwise."""
    for family in FAMILIES:
        if family.name == name:
            return family
    known = ", ".join(f.name for f in FAMILIES)
    raise ConfigError("family", name, f"unknown servo family; known: {known}")


def families_of(vendor: str) -> tuple[ServoFamily, ...]:
    """Every family of one vendor's model data (``"dynamixel"``, ``"feetech"``), newest
    protocol first."""
    return tuple(f for f in FAMILIES if f.vendor == vendor)


def family_for(table: ServoTable, protocol: float | None = None) -> ServoFamily:
    """The family a servo of model ``table`` speaks on a bus of ``protocol`` (None: the model's
    default, its first listed protocol).

    Raises ConfigError naming the model and the protocols it has when it cannot speak
    ``protocol`` (an XL330 in Protocol 1.0, an AX-12A in 2.0).
    """
    wanted = table.protocols[0] if protocol is None else float(protocol)
    for family in families_of(table.family):
        if family.protocol == wanted and family.speaks(table):
            return family
    has = ", ".join(f"{p:.1f}" for p in table.protocols)
    raise ConfigError(
        "protocol",
        f"{wanted:.1f}",
        f"{table.model} servos speak Protocol {has} only; set [bus] protocol to one of them",
    )


__all__ = [
    "FAMILIES",
    "READ_METHODS",
    "Capabilities",
    "DynamixelProtocol1",
    "DynamixelProtocol2",
    "EepromLock",
    "FeetechSCS",
    "FeetechSTS",
    "ServoFamily",
    "WireCost",
    "families_of",
    "family_for",
    "family_named",
]
