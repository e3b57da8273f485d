"""Joint radians <-> servo position ticks for a whole chain, vectorised for the control loop.

The formula and the calibration convention are snakebot.servo.ticks' (software only: the servo's
Drive Mode reverse bit must stay 0 and Homing Offset is not used for calibration). A joint at 0 rad
sits at the servo's centre tick plus ``direction * zero_offset_rad`` worth of ticks, and the
servo's own centre reads as ``-zero_offset_rad``. Velocities follow the direction only.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from snakebot.config.schema import RobotConfig
from snakebot.servo.ticks import TickModel


@dataclass(frozen=True)
class TickConverter:
    """Vectorised rad <-> tick conversion for a chain, head to tail; arrays have shape (N,).

    ``lower_ticks``/``upper_ticks`` are the joint limits in ticks (``lower_ticks <= upper_ticks``
    whatever the direction); goals are clipped to them at the bus edge. The conversion is folded
    into one gain and one bias per joint, so the control loop pays two array operations per way.
    """

    ticks: TickModel
    zero_offset_rad: np.ndarray
    direction: np.ndarray
    lower_rad: np.ndarray
    upper_rad: np.ndarray
    lower_ticks: np.ndarray
    upper_ticks: np.ndarray
    _tick_gain: np.ndarray = field(init=False, repr=False, compare=False)
    _tick_bias: np.ndarray = field(init=False, repr=False, compare=False)
    _rad_gain: np.ndarray = field(init=False, repr=False, compare=False)
    _rad_bias: np.ndarray = field(init=False, repr=False, compare=False)
    _goal_terms: list[tuple[float, float, int, int]] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        k = self.ticks.ticks_per_rad
        centre = self.ticks.centre
        derived = {
            "_tick_gain": self.direction * k,
            "_tick_bias": centre + self.direction * self.zero_offset_rad * k,
            "_rad_gain": self.direction / k,
            "_rad_bias": -self.direction * centre / k - self.zero_offset_rad,
        }
        for name, value in derived.items():
            object.__setattr__(self, name, np.asarray(value, dtype=float))
        terms = zip(
            self._tick_gain.tolist(),
            self._tick_bias.tolist(),
            self.lower_ticks.tolist(),
            self.upper_ticks.tolist(),
            strict=True,
        )
        object.__setattr__(self, "_goal_terms", list(terms))

    @classmethod
    def for_robot(cls, robot: RobotConfig) -> TickConverter:
        """The converter for a robot's joints and servo resolution."""
        model = robot.servo.physics.ticks
        offset = np.array([j.zero_offset_rad for j in robot.joints], dtype=float)
        direction = np.array([j.direction for j in robot.joints], dtype=float)
        lower, upper = robot.lower_rad.astype(float), robot.upper_rad.astype(float)
        k = model.ticks_per_rad
        a = model.centre + direction * (lower + offset) * k
        b = model.centre + direction * (upper + offset) * k
        # Limits round inwards so a clipped goal never lands outside the configured range.
        lo = np.ceil(np.minimum(a, b) - 1e-9).astype(np.int64)
        hi = np.floor(np.maximum(a, b) + 1e-9).astype(np.int64)
        lo, hi = np.maximum(lo, model.minimum), np.minimum(hi, model.maximum)
        return cls(model, offset, direction, lower, upper, lo, hi)

    @property
    def joint_count(self) -> int:
        """N."""
        return int(self.direction.shape[0])

    @property
    def rad_per_tick(self) -> float:
        """Resolution (rad per tick)."""
        return self.ticks.rad_per_tick

    def to_ticks(self, angle_rad: np.ndarray) -> np.ndarray:
        """Joint angles (rad, (N,)) to goal ticks (int64, (N,)), unclipped."""
        ticks: np.ndarray = np.rint(angle_rad * self._tick_gain + self._tick_bias).astype(np.int64)
        return ticks

    def clip_ticks(self, ticks: np.ndarray) -> np.ndarray:
        """Ticks clipped to the joint limits (int64, (N,))."""
        clipped: np.ndarray = np.minimum(np.maximum(ticks, self.lower_ticks), self.upper_ticks)
        return clipped

    @property
    def goal_terms(self) -> list[tuple[float, float, int, int]]:
        """Per joint (tick gain, tick bias, lowest and highest goal tick): the joint limits."""
        return list(self._goal_terms)

    def goal_ticks(
        self,
        angle_rad: np.ndarray | Sequence[float],
        terms: Sequence[tuple[float, float, int, int]] | None = None,
    ) -> tuple[list[int], bool]:
        """Goal ticks clipped to the limits, and whether any joint was clipped; ValueError for NaN.

        ``terms`` replaces :attr:`goal_terms` (the backend widens a joint's bounds while it
        brings a joint found outside its limits back in). Plain floats on purpose: this runs once
        per control cycle, where a few numpy calls on cold caches cost more than the loop (see
        plans.py).
        """
        angles = angle_rad.tolist() if isinstance(angle_rad, np.ndarray) else list(angle_rad)
        ticks, clipped = [], False
        for angle, (gain, bias, low, high) in zip(angles, terms or self._goal_terms, strict=True):
            value = angle * gain + bias
            if not low <= value <= high:  # NaN fails both comparisons
                if not math.isfinite(value):
                    raise ValueError(f"command holds non-finite angles: {angles}")
                value, clipped = (low if value < low else high), True
            ticks.append(round(value))
        return ticks, clipped

    def state_terms(self) -> list[tuple[float, float]]:
        """Per joint (gain, bias) with ``angle_rad = ticks * gain + bias``, for plain floats."""
        return list(zip(self._rad_gain.tolist(), self._rad_bias.tolist(), strict=True))

    def to_rad(self, ticks: np.ndarray) -> np.ndarray:
        """Present ticks ((N,), any int dtype) to joint angles (rad, (N,))."""
        angle: np.ndarray = ticks * self._rad_gain + self._rad_bias
        return angle
