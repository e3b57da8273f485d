"""One home for the servo facts that are not bus-specific, shared by config, twin and bus.

``gains``: how the Position P/D Gain registers map to stiffness (N·m/rad) and damping (N·m·s/rad),
and back. ``ticks``: the joint-radian <-> position-tick formula and each model's tick model.
``factory``: the ID and baud rate a servo leaves the factory with. The datasheet numbers themselves
(stall torque, no-load speed, model number, resolution, register ranges and defaults) live in the
control-table data, ``snakebot/servo_tables/data/<model>.toml``; the servo file names the model and
adds only what the datasheet does not say. Nothing here imports mujoco or dynamixel_sdk.
"""

from snakebot.servo.factory import FACTORY_BAUD, FACTORY_ID
from snakebot.servo.gains import COMPLIANCE_SLOPES, ComplianceMapping, GainMapping
from snakebot.servo.ticks import (
    X_SERIES_TICKS,
    TickModel,
    centre_tick,
    rad_per_tick,
    rad_to_ticks,
    ticks_to_rad,
)

__all__ = [
    "COMPLIANCE_SLOPES",
    "FACTORY_BAUD",
    "FACTORY_ID",
    "X_SERIES_TICKS",
    "ComplianceMapping",
    "GainMapping",
    "TickModel",
    "centre_tick",
    "rad_per_tick",
    "rad_to_ticks",
    "ticks_to_rad",
]
