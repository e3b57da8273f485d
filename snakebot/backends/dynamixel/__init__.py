"""The servo-chain backend: a bus layer over a vendor SDK and the Backend contract in SI units.

``DynamixelBackend(robot)`` drives a configured servo chain; ``DynamixelBus`` is the register-level
bus (also for tools). The link under the bus follows the servo family's vendor (``links.py``):
Dynamixel servos through ``sdk.py``, the only importer of ``dynamixel_sdk``; Feetech servos
through ``snakebot.backends.feetech.sdk``, the only importer of ``scservo_sdk``. The backend
names ``dynamixel`` and ``feetech`` are this chain, each for its vendor's robots.
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
