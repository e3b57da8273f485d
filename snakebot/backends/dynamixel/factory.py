"""``make_dynamixel``: the servo chain's factory in the backend registry (name ``dynamixel``)."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from snakebot.backends.dynamixel.backend import DynamixelBackend
from snakebot.config import RobotConfig
from snakebot.config.ports import check_port
from snakebot.errors import ConfigError


def make_dynamixel(
    robot: RobotConfig,
    *,
    port: str | None = None,
    baud: int | str | None = None,
    allow_extra_servos: bool = False,
    port_handler_factory: Any = None,
    clock: Callable[[], float] = time.monotonic,
    sleep: Callable[[float], None] = time.sleep,
) -> DynamixelBackend:
    """The servo chain of ``robot``, unconnected (no port is opened here).

    ``port`` and ``baud`` default to the robot file's bus; ``allow_extra_servos`` leaves servos
    the file does not name alone instead of refusing them. ConfigError for a bad port or baud,
    or when ``robot`` is a mass-spring body (those run on the twin only).
    """
    if not isinstance(robot, RobotConfig):
        name = getattr(robot, "name", type(robot).__name__)
        raise ConfigError(
            str(name), "", "is a mass-spring body: it runs on the twin only (no servos to drive)"
        )
    if port is not None and port_handler_factory is None:
        port = check_port(str(port), source="port")
    return DynamixelBackend(
        robot,
        port=port,
        baud=_baud(baud),
        allow_extra_servos=bool(allow_extra_servos),
        port_handler_factory=port_handler_factory,
        clock=clock,
        sleep=sleep,
    )


def _baud(value: int | str | None) -> int | None:
    if value is None:
        return None
    try:
        baud = int(value)
    except (TypeError, ValueError):
        raise ConfigError("baud", "", f"expected a baud rate in bit/s, got {value!r}") from None
    if baud <= 0:
        raise ConfigError("baud", "", f"expected a positive baud rate, got {baud}")
    return baud
