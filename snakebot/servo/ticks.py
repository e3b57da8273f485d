"""Joint radians <-> servo position ticks: the one formula, used by the bus, setup and emulator.

    ticks = centre + direction * (angle_rad + zero_offset_rad) * ticks_per_rev / (2 pi)
    angle_rad = direction * (ticks - centre) * 2 pi / ticks_per_rev - zero_offset_rad

with ``centre = ticks_per_rev // 2`` (2048 on a 4096-tick X-series servo; the resolution comes
from the control table) and ``direction`` +1 or -1. A joint at 0 rad sits at tick
``centre + direction * zero_offset_rad * ticks_per_rev / (2 pi)``.
"""

from __future__ import annotations

import math


def centre_tick(ticks_per_rev: int) -> int:
    """The tick of joint zero before calibration: half a turn (2048 of 4096)."""
    return ticks_per_rev // 2


def ticks_per_rad(ticks_per_rev: int) -> float:
    """Position ticks per radian."""
    return ticks_per_rev / (2.0 * math.pi)


def rad_per_tick(ticks_per_rev: int) -> float:
    """Radians per position tick, the resolution (0.088 deg on a 4096-tick servo)."""
    return 2.0 * math.pi / ticks_per_rev


def rad_to_ticks(
    angle_rad: float, *, ticks_per_rev: int, zero_offset_rad: float = 0.0, direction: int = 1
) -> int:
    """One joint angle (rad) to the nearest servo position tick."""
    k = ticks_per_rad(ticks_per_rev)
    return round(centre_tick(ticks_per_rev) + direction * (angle_rad + zero_offset_rad) * k)


def ticks_to_rad(
    ticks: int, *, ticks_per_rev: int, zero_offset_rad: float = 0.0, direction: int = 1
) -> float:
    """One servo position tick to the joint angle (rad)."""
    return (
        direction * (ticks - centre_tick(ticks_per_rev)) * rad_per_tick(ticks_per_rev)
        - zero_offset_rad
    )
