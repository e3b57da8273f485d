"""The servo chain's factories in the backend registry: ``make_dynamixel`` (name ``dynamixel``)
and ``make_feetech`` (name ``feetech``): one chain backend, each refusing the other vendor's
servos so a backend name keeps meaning one vendor."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.config import RobotConfig
from snakebot.config.ports import check_port
from snakebot.errors import ConfigError
from snakebot.servo_tables import table_for_model

VENDOR_NAMES = {"dynamixel": "Dynamixel", "feetech": "Feetech"}


def make_dynamixel(
    robot: RobotConfig,
    *,
    port: str | None = None,
    baud: int | str | None = None,
    allow_extra_servos: bool = False,
    port_handler_factory: Any = None,
    clock: Callable[[], float] = time.monotonic,
    sleep: Callable[[float], None] = time.sleep,
) -> ServoChainBackend:
    """The Dynamixel servo chain of ``robot``, unconnected (no port is opened here).

    ``port`` and ``baud`` default to the robot file's bus; ``allow_extra_servos`` leaves servos
    the file does not name alone instead of refusing them. ConfigError for a bad port or baud,
    when ``robot`` is a mass-spring body (those run on the twin only) or when its servos are
    not Dynamixels (a Feetech robot runs on the ``feetech`` backend).
    """
    return make_chain(
        robot,
        "dynamixel",
        port=port,
        baud=baud,
        allow_extra_servos=allow_extra_servos,
        port_handler_factory=port_handler_factory,
        clock=clock,
        sleep=sleep,
    )


def make_feetech(
    robot: RobotConfig,
    *,
    port: str | None = None,
    baud: int | str | None = None,
    allow_extra_servos: bool = False,
    port_handler_factory: Any = None,
    clock: Callable[[], float] = time.monotonic,
    sleep: Callable[[float], None] = time.sleep,
) -> ServoChainBackend:
    """The Feetech (STS/SCS) servo chain of ``robot``, unconnected: the same chain backend
    talking through scservo_sdk (``snakebot.backends.feetech``); options as
    :func:`make_dynamixel`. ConfigError when the robot's servos are not Feetech's."""
    return make_chain(
        robot,
        "feetech",
        port=port,
        baud=baud,
        allow_extra_servos=allow_extra_servos,
        port_handler_factory=port_handler_factory,
        clock=clock,
        sleep=sleep,
    )


def make_chain(
    robot: RobotConfig,
    vendor: str,
    *,
    port: str | None = None,
    baud: int | str | None = None,
    allow_extra_servos: bool = False,
    port_handler_factory: Any = None,
    clock: Callable[[], float] = time.monotonic,
    sleep: Callable[[float], None] = time.sleep,
) -> ServoChainBackend:
    """The servo chain of ``robot`` on the backend of ``vendor`` (its name); ConfigError naming
    the robot file's servo and the backend that drives it when the vendors differ."""
    if not isinstance(robot, RobotConfig):
        name = getattr(robot, "name", type(robot).__name__)
        raise ConfigError(
            str(name), "", "is a mass-spring body: it runs on the twin only (no servos to drive)"
        )
    have = table_for_model(robot.servo.name).family
    if have != vendor:
        raise ConfigError(
            robot.source,
            "servo",
            f"{robot.servo.name} is a {VENDOR_NAMES.get(have, have)} servo, not a "
            f"{VENDOR_NAMES.get(vendor, vendor)} one: robot {robot.name} runs on the "
            f"{have} backend",
        )
    if port is not None and port_handler_factory is None:
        port = check_port(str(port), source="port")
    return ServoChainBackend(
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
