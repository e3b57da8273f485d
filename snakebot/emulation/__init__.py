"""A byte-level servo bus emulator that serves the unmodified vendor SDKs: Dynamixel Protocol 2.0
and 1.0 (ROBOTIS's SDK) and Feetech FT-SCS (Feetech's `scservo_sdk`), all on one wire; each
servo's packets are served by its model's vendor.

Core (no transport): `VirtualServo` (control table + firmware rules + motion model) and
`EmulatedChain` (servos on one bus, bytes in, timed bytes out, fault injection). Ways in:
`dxlemu://<name>` URLs for pyserial (`register_chain`, and `snakebot.emulation.port.
EmulatedPortHandler` / `snakebot.emulation.port_feetech.EmulatedScsPortHandler` for the SDKs) and
a pseudo-terminal (`snakebot.emulation.pty_server.PtyServer`). Those import the SDKs and termios,
so they are not imported here.
"""

from snakebot.emulation.alarms import Fault
from snakebot.emulation.chain import EmulatedChain, make_chain_for_ids
from snakebot.emulation.errors import EmulationError
from snakebot.emulation.faults import Faults
from snakebot.emulation.firmware import HardwareError
from snakebot.emulation.motion import (
    ChainPhysics,
    ExternalMotion,
    MotionModel,
    MotorState,
    OperatingMode,
    ProfileMotion,
    ServoCommand,
)
from snakebot.emulation.registry import (
    chain_url,
    install_url_handler,
    lookup_chain,
    register_chain,
    registered,
    unregister_chain,
)
from snakebot.emulation.virtual_servo import VirtualServo
from snakebot.emulation.wire import BusReply

__all__ = [
    "BusReply",
    "ChainPhysics",
    "EmulatedChain",
    "EmulationError",
    "ExternalMotion",
    "Fault",
    "Faults",
    "HardwareError",
    "MotionModel",
    "MotorState",
    "OperatingMode",
    "ProfileMotion",
    "ServoCommand",
    "VirtualServo",
    "chain_url",
    "install_url_handler",
    "lookup_chain",
    "make_chain_for_ids",
    "register_chain",
    "registered",
    "unregister_chain",
]
