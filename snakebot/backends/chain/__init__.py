"""The servo-chain backend: a bus layer over a vendor SDK and the Backend contract in SI units.

``ServoChainBackend(robot)`` drives a configured servo chain; ``ServoBus`` is the register-level
bus (also for tools). The link under the bus follows the servo family's vendor (``links.py``):
Dynamixel servos through ``sdk.py``, the only importer of ``dynamixel_sdk``; Feetech servos
through ``snakebot.backends.feetech.sdk``, the only importer of ``scservo_sdk``. The backend
names ``dynamixel`` and ``feetech`` are this chain, each for its vendor's robots.
"""

from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.backends.chain.bus import ServoBus
from snakebot.backends.chain.faults import (
    ChainMismatchError,
    ExtraServosWarning,
    HardwareFaultError,
    PoseOutsideLimitsError,
    ServoSettingsError,
    ServoSettingsWarning,
    ServoStatusError,
    StopIncompleteError,
    SyncReadError,
    TrackingError,
    WatchdogTripError,
    decode_hardware_error,
)
from snakebot.backends.chain.supervision import TrackingLimits
from snakebot.backends.chain.ticks import TickConverter

__all__ = [
    "ChainMismatchError",
    "ExtraServosWarning",
    "HardwareFaultError",
    "PoseOutsideLimitsError",
    "ServoBus",
    "ServoChainBackend",
    "ServoSettingsError",
    "ServoSettingsWarning",
    "ServoStatusError",
    "StopIncompleteError",
    "SyncReadError",
    "TickConverter",
    "TrackingError",
    "TrackingLimits",
    "WatchdogTripError",
    "decode_hardware_error",
]
