"""snakebot in a ROS 2 system: one node owning the backend, the safety layer and the cycle.

``snakebot ros2 --robot NAME --backend twin|dynamixel|...`` serves a robot; :func:`run_node`
does the same for a connected :class:`snakebot.Snake`. The interface (topics, types, QoS,
parameters) is data in snakebot.ros2.topics; docs/ros2.md describes it. Importing this package
does not import rclpy (the ``ros2`` extra: ``pip install 'snakebot[ros2]'``); running a node
does, and :func:`require_rclpy` says what to install when it is missing.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from snakebot.errors import MissingDependencyError
from snakebot.ros2.commands import (
    Command,
    CommandError,
    CommandInbox,
    JointTargets,
    Steer,
    TimeoutAction,
    Trajectory,
)
from snakebot.ros2.options import NodeOptions, joint_names, loopback_environment
from snakebot.ros2.serve import ServeResult

if TYPE_CHECKING:
    from snakebot.ros2.node import run_node

INSTALL = "pip install 'snakebot[ros2]'"
"""What installs ROS 2's Python client and messages (wheels from PyPI; no ROS install)."""
_MODULES = (
    "rclpy",
    "sensor_msgs.msg",
    "geometry_msgs.msg",
    "trajectory_msgs.msg",
    "diagnostic_msgs.msg",
)

__all__ = [
    "INSTALL",
    "Command",
    "CommandError",
    "CommandInbox",
    "JointTargets",
    "NodeOptions",
    "ServeResult",
    "Steer",
    "TimeoutAction",
    "Trajectory",
    "joint_names",
    "loopback_environment",
    "require_rclpy",
    "run_node",
]


def require_rclpy() -> None:
    """Import rclpy and the message packages the node uses; MissingDependencyError naming the
    module and the install command when one is missing."""
    for module in _MODULES:
        try:
            importlib.import_module(module)
        except ImportError as exc:
            raise MissingDependencyError(
                f"snakebot ros2 needs ROS 2's Python client and messages ({module} is not "
                f"installed): {INSTALL} (wheels from PyPI, no ROS installation needed)"
            ) from exc


def __getattr__(name: str) -> Any:
    if name == "run_node":
        require_rclpy()
        from snakebot.ros2.node import run_node

        return run_node
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
