"""Dynamixel hardware backend: a bus layer over dynamixel_sdk and the Backend contract in SI units.

``DynamixelBackend(robot)`` drives a configured servo chain; ``DynamixelBus`` is the register-level
bus (also for tools). Only ``sdk.py`` imports ``dynamixel_sdk``.
"""

from snakebot.backends.dynamixel.backend import DynamixelBackend
from snakebot.backends.dynamixel.bus import DynamixelBus
from snakebot.backends.dynamixel.faults import (
    ChainMismatchError,
    DynamixelSettingsWarning,
    ExtraServosWarning,
    HardwareFaultError,
    PoseOutsideLimitsError,
    ServoSettingsError,
    ServoStatusError,
    StopIncompleteError,
    SyncReadError,
    TrackingError,
    WatchdogTripError,
    decode_hardware_error,
)
from snakebot.backends.dynamixel.supervision import TrackingLimits
from snakebot.backends.dynamixel.ticks import TickConverter

__all__ = [
    "ChainMismatchError",
    "DynamixelBackend",
    "DynamixelBus",
    "DynamixelSettingsWarning",
    "ExtraServosWarning",
    "HardwareFaultError",
    "PoseOutsideLimitsError",
    "ServoSettingsError",
    "ServoStatusError",
    "StopIncompleteError",
    "SyncReadError",
    "TickConverter",
    "TrackingError",
    "TrackingLimits",
    "WatchdogTripError",
    "decode_hardware_error",
]
