"""Hardware-in-the-loop tests: skipped unless SNAKEBOT_PORT names a real servo bus (Dynamixel or
Feetech: the robot file's servo model says which).

A robot owner runs them against the snake on the desk::

    SNAKEBOT_PORT=/dev/ttyUSB0 SNAKEBOT_ROBOT=snake12 pytest tests/hardware -v

``SNAKEBOT_ROBOT`` is a robot name from firmware_configs/robots/ or a path to a robot .toml (it
must describe the chain on that port). The servos move: a small wave for 2 s, then the robot's
stop ramp, and the stop policy is left applied. Lay the snake flat with room to move.
"""

from __future__ import annotations

import os

import pytest

from snakebot.config import RobotConfig, load_robot


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Skip every test marked ``hardware`` unless SNAKEBOT_PORT is set."""
    if os.environ.get("SNAKEBOT_PORT"):
        return
    skip = pytest.mark.skip(
        reason="needs a real servo bus: set SNAKEBOT_PORT (and SNAKEBOT_ROBOT) to run"
    )
    for item in items:
        if "hardware" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def port() -> str:
    """The serial port of the bus under test (SNAKEBOT_PORT)."""
    return os.environ["SNAKEBOT_PORT"]


@pytest.fixture(scope="session")
def robot() -> RobotConfig:
    """The robot file that describes the chain on that port (SNAKEBOT_ROBOT)."""
    name = os.environ.get("SNAKEBOT_ROBOT")
    if not name:
        pytest.fail("set SNAKEBOT_ROBOT to the robot name or .toml that describes this chain")
    return load_robot(name)
