"""Joint radians <-> servo position ticks: the one formula, used by the bus, setup and emulator.

    ticks = centre + direction * (angle_rad + zero_offset_rad) * ticks_per_rad
    angle_rad = direction * (ticks - centre) / ticks_per_rad - zero_offset_rad

A model's :class:`TickModel` (from its control-table data) gives ``centre`` and ``ticks_per_rad``:
an X-series servo counts 4096 ticks over a full turn centred at 2048, an AX-12A 1024 ticks over
300 degrees centred at 512. ``direction`` is +1 or -1. A joint at 0 rad sits at tick
``centre + direction * zero_offset_rad * ticks_per_rad``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class TickModel:
    """How one servo model counts position: ``count`` ticks over ``travel_deg`` degrees.

    ``centre`` is joint zero before calibration; ``minimum``/``maximum`` the register's range of
    goal positions; ``sign`` how the position register encodes a negative value: "unsigned"
    (never negative), "twos" (two's complement) or "magnitude" (sign-magnitude, bit
    ``sign_bit``), so the family's codec decodes it in one place.
    """

    count: int = 4096
    travel_deg: float = 360.0
    centre: int = 2048
    minimum: int = 0
    maximum: int = 4095
    sign: str = "unsigned"
    sign_bit: int = 15

    def __post_init__(self) -> None:
        if self.count <= 0 or not 0.0 < self.travel_deg <= 360.0:
            raise ValueError(f"a tick model needs count > 0 and 0 < travel <= 360 deg: {self}")
        if not self.minimum <= self.centre <= self.maximum:
            raise ValueError(f"tick centre {self.centre} outside {self.minimum}..{self.maximum}")
        if self.sign not in ("unsigned", "twos", "magnitude"):
            raise ValueError(f"tick sign must be unsigned, twos or magnitude, not {self.sign!r}")

    @property
    def ticks_per_rad(self) -> float:
        """Position ticks per radian (651.9 on a 4096-tick turn, 195.6 on an AX-12A)."""
        return self.count / math.radians(self.travel_deg)

    @property
    def rad_per_tick(self) -> float:
        """Radians per tick, the resolution (0.088 deg on an X-series servo, 0.29 on an AX)."""
        return math.radians(self.travel_deg) / self.count

    @property
    def ticks_per_rev(self) -> float:
        """Ticks a full turn would take (4096 on an X-series servo, 1228.8 on an AX-12A)."""
        return self.ticks_per_rad * 2.0 * math.pi

    @property
    def travel_rad(self) -> tuple[float, float]:
        """The joint angles (rad, before offset and direction) at ``minimum`` and ``maximum``."""
        return (
            (self.minimum - self.centre) / self.ticks_per_rad,
            (self.maximum - self.centre) / self.ticks_per_rad,
        )

    def to_ticks(
        self, angle_rad: float, *, zero_offset_rad: float = 0.0, direction: int = 1
    ) -> int:
        """One joint angle (rad) to the nearest position tick (not clamped to the range)."""
        return round(self.centre + direction * (angle_rad + zero_offset_rad) * self.ticks_per_rad)

    def to_rad(self, ticks: int, *, zero_offset_rad: float = 0.0, direction: int = 1) -> float:
        """One position tick to the joint angle (rad)."""
        return direction * (ticks - self.centre) / self.ticks_per_rad - zero_offset_rad


X_SERIES_TICKS = TickModel()
"""4096 ticks per turn centred at 2048: every X-series and MX servo."""


def centre_tick(ticks: TickModel) -> int:
    """The tick of joint zero before calibration (2048 on an X-series servo, 512 on an AX)."""
    return ticks.centre


def ticks_per_rad(ticks: TickModel) -> float:
    """Position ticks per radian."""
    return ticks.ticks_per_rad


def rad_per_tick(ticks: TickModel) -> float:
    """Radians per position tick, the resolution."""
    return ticks.rad_per_tick


def rad_to_ticks(
    angle_rad: float, *, ticks: TickModel, zero_offset_rad: float = 0.0, direction: int = 1
) -> int:
    """One joint angle (rad) to the nearest servo position tick."""
    return ticks.to_ticks(angle_rad, zero_offset_rad=zero_offset_rad, direction=direction)


def ticks_to_rad(
    tick: int, *, ticks: TickModel, zero_offset_rad: float = 0.0, direction: int = 1
) -> float:
    """One servo position tick to the joint angle (rad)."""
    return ticks.to_rad(tick, zero_offset_rad=zero_offset_rad, direction=direction)
