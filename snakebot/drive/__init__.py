"""Driving a snake live: input sources (terminal, gamepad, script), the key map, the drive loop
and its terminal display. The gait side (integrated phases, blends) is snakebot.gaits.live."""

from snakebot.drive.controller import DriveController, GaitChoice
from snakebot.drive.run import DriveCycle, DriveObserver, DriveResult, run_drive
from snakebot.drive.sources import (
    DriveInputError,
    InputDeviceError,
    InputEvent,
    InputSource,
    ScriptRecorder,
    ScriptSource,
    parse_script,
)

__all__ = [
    "DriveController",
    "DriveCycle",
    "DriveInputError",
    "DriveObserver",
    "DriveResult",
    "GaitChoice",
    "InputDeviceError",
    "InputEvent",
    "InputSource",
    "ScriptRecorder",
    "ScriptSource",
    "parse_script",
    "run_drive",
]
