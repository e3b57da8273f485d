"""Reading the optional parts of the twin's servo model: electrics, overload, encoder and IMU
noise (docs/physics.md, "A fuller servo model").

They live in the servo file's ``[twin]`` table (datasheet facts of the model) and may be
overridden per robot in the robot file's ``[twin.servo]`` (values ``snakebot sysid`` fitted).
Every part is off (None) unless set, and then the twin is exactly as before. The P-gain divisor
is not one of them: it is the servo file's ``physics.p_gain_divisor`` (snakebot.servo.GainMapping),
which a robot's ``[twin.servo]`` may override (config/loader.py).
"""

from __future__ import annotations

from dataclasses import fields, replace

from snakebot.config.bounds import Bounds
from snakebot.config.fields import Table
from snakebot.config.servos.extras import ServoExtras

BOUNDS: dict[str, Bounds] = {
    "stall_current_a": Bounds(0.01, 50, "A", "datasheet stall current; an XL430's is 1.3 A"),
    "battery_resistance_ohm": Bounds(0, 10, "Ω", "supply internal resistance; a LiPo's ~0.05"),
    "overload_trip_s": Bounds(0.05, 60, "s", "stall time before the overload protection trips"),
    "encoder_noise_rad": Bounds(0, 0.1, "rad", "position reading noise (1 tick = 0.0015 rad)"),
    "quantise_encoder": Bounds(0, 1, "", "1: positions in whole encoder ticks"),
    "imu_gyro_noise_rad_s": Bounds(0, 1, "rad/s", "head gyro noise; an MPU-6050's is ~0.005"),
}
"""Keys of the servo file's ``[twin]`` and the robot file's ``[twin.servo]`` (same meaning)."""


def read_servo_extras(table: Table, extras: ServoExtras) -> ServoExtras:
    """The extras in ``table``, each defaulting to the value in ``extras``.

    Marks the keys read; ConfigError naming the file and key for a value out of BOUNDS.
    """
    changes: dict[str, object] = {}
    for item in fields(ServoExtras):
        if not table.has(item.name):
            continue
        if item.name == "quantise_encoder":
            changes[item.name] = table.integer(item.name, choices=(0, 1))
        else:
            changes[item.name] = table.number(item.name, within=BOUNDS[item.name])
    extras = replace(extras, **changes)  # type: ignore[arg-type]
    if extras.battery_resistance_ohm is not None and extras.stall_current_a is None:
        raise table.error(
            "battery_resistance_ohm",
            "battery sag needs the current draw: set stall_current_a "
            "(the datasheet's stall current) in the servo file's [twin] too",
        )
    return extras
