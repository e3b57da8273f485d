"""How a node is set up, as data: its options, the joint names, the DDS loopback settings."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from snakebot.config import RobotConfig
from snakebot.drive.controller import GaitChoice
from snakebot.drive.setup import DEFAULT_SMOOTHING_S, DEFAULT_TRANSITION_S, default_gaits
from snakebot.errors import ConfigError
from snakebot.ros2.commands import TimeoutAction
from snakebot.ros2.topics import DEFAULT_COMMAND_TIMEOUT_S, NODE_NAME

LOOPBACK_PROFILE = Path(__file__).with_name("fastdds-loopback.xml")
"""Fast DDS profile: one UDPv4 transport on 127.0.0.1, the built-in transports off."""


def loopback_environment() -> dict[str, str]:
    """The three settings that keep DDS on this machine (set them before rclpy starts):
    discovery on localhost only, Fast DDS, and its loopback-only profile."""
    return {
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST",
        "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
        "FASTDDS_DEFAULT_PROFILES_FILE": str(LOOPBACK_PROFILE),
    }


def joint_names(robot: RobotConfig) -> tuple[str, ...]:
    """The joints' names, head to tail: ``joint0`` .. ``joint{N-1}``, the names the twin's
    model gives them (robot files number joints, they do not name them)."""
    return tuple(f"joint{index}" for index in range(robot.joint_count))


def split_gait_params(text: str) -> list[str]:
    """``KEY=VALUE`` items of the ``gait_params`` parameter (separated by commas or spaces)."""
    return [item for item in re.split(r"[,\s]+", text.strip()) if item]


@dataclass(frozen=True)
class NodeOptions:
    """The node's settings.

    ``rate_hz`` control cycles per second; ``command_timeout_s`` without a command before
    ``on_timeout`` ("stop": rest pose, then the stop policy, the node ends; "halt": speed and
    turn to 0, the node serves on; 0 s: no watchdog); ``gaits`` the gaits ``gait`` may start
    with (default: the robot's first drive gait), the first driven; ``smoothing_s`` and
    ``transition_s`` as ``snakebot drive``'s; ``node_name``; ``ros_args`` rclpy's own
    arguments, its ``--ros-args`` marker first (remaps, ``-p`` parameters, the namespace).
    Raises ConfigError naming the field for a bad value.
    """

    rate_hz: float = 100.0
    command_timeout_s: float = DEFAULT_COMMAND_TIMEOUT_S
    on_timeout: TimeoutAction = "stop"
    gaits: tuple[GaitChoice, ...] = ()
    smoothing_s: float = DEFAULT_SMOOTHING_S
    transition_s: float = DEFAULT_TRANSITION_S
    node_name: str = NODE_NAME
    ros_args: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        if not (self.rate_hz > 0 and math.isfinite(self.rate_hz)):
            raise ConfigError("rate_hz", "", f"expected a positive number, got {self.rate_hz!r}")
        if not (self.command_timeout_s >= 0 and math.isfinite(self.command_timeout_s)):
            raise ConfigError(
                "command_timeout_s", "", f"expected seconds >= 0, got {self.command_timeout_s!r}"
            )
        if self.on_timeout not in ("stop", "halt"):
            raise ConfigError("on_timeout", "", f"expected stop or halt, got {self.on_timeout!r}")

    def gait_choices(self, robot: RobotConfig) -> tuple[GaitChoice, ...]:
        """``gaits``, or the robot's first drive gait with its defaults."""
        return self.gaits or (GaitChoice(default_gaits(robot)[0]),)
