"""Robot and servo configuration: schema (frozen dataclasses) and a validating loader."""

from snakebot.config.loader import load_robot, robot_names
from snakebot.config.schema import JointConfig, RobotConfig, ServoModel

__all__ = ["JointConfig", "RobotConfig", "ServoModel", "load_robot", "robot_names"]
