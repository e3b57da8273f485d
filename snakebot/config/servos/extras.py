"""The optional parts of the twin's servo model as values (read by config/servos/twin.py)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ServoExtras:
    """Optional servo-model parts; None (or 0) leaves each out.

    ``stall_current_a``: datasheet stall current at the nominal voltage; with it the twin
    reports current draw and an electrical cost of transport (winding resistance R = V_nom /
    I_stall, torque constant kt = tau_stall / I_stall at the output shaft).
    ``battery_resistance_ohm``: the supply's internal resistance; the supply voltage then sags
    by R * (total current), and the torque-speed line with it (needs ``stall_current_a``).
    ``overload_trip_s``: a servo at its torque limit, not moving, for this long turns its
    torque off and latches Overload, as the firmware's protection does.
    ``encoder_noise_rad``: standard deviation of Gaussian reading noise on positions (seeded).
    ``quantise_encoder``: 1 rounds read positions to whole encoder ticks.
    ``imu_gyro_noise_rad_s``: standard deviation of the head IMU's angular-rate noise (seeded).
    """

    stall_current_a: float | None = None
    battery_resistance_ohm: float | None = None
    overload_trip_s: float | None = None
    encoder_noise_rad: float | None = None
    quantise_encoder: int = 0
    imu_gyro_noise_rad_s: float | None = None

    @property
    def changes_physics(self) -> bool:
        """Whether any part alters what the twin computes (not just what it reports)."""
        return self.battery_resistance_ohm is not None or self.overload_trip_s is not None


NO_EXTRAS = ServoExtras()
