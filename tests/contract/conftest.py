"""Backends under the contract: each entry builds a fresh, unconnected backend for a robot.

A backend joins the contract by adding a factory here; every test in this folder then runs on it.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from dataclasses import replace

import pytest

from snakebot.backends.base import Backend
from snakebot.backends.dynamixel import DynamixelBackend
from snakebot.backends.twin import GroundFriction, TwinBackend
from snakebot.config import load_robot
from snakebot.emulation import make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler

BackendFactory = Callable[[str], Backend]


def _twin(robot: str) -> Backend:
    # Frictionless ground: the contract checks the servo loop, not locomotion.
    return TwinBackend(load_robot(robot), friction=GroundFriction(0.0, 0.0))


FACTORIES: dict[str, Callable[[], Iterator[BackendFactory]]] = {}


def _twin_factory() -> Iterator[BackendFactory]:
    yield _twin


FACTORIES["twin"] = _twin_factory


def _softbody(robot: str) -> Backend:
    """Miller's snake lattice with one yaw muscle channel per joint of ``robot``, no friction."""
    from snakebot.backends.softbody import SoftBodyBackend
    from snakebot.config.body_loader import load_body

    body = load_body("snake")
    segments = load_robot(robot).joint_count
    body = replace(
        body,
        lattice=replace(body.lattice, segments=segments),
        muscles=replace(body.muscles, channels=("yaw",)),
    )
    return SoftBodyBackend(body, friction=0.0)


def _softbody_factory() -> Iterator[BackendFactory]:
    yield _softbody


FACTORIES["softbody"] = _softbody_factory


def _dynamixel_factory() -> Iterator[BackendFactory]:
    """The real dynamixel_sdk over the in-process emulator; the bus clock is the backend's time."""
    with contextlib.ExitStack() as stack:

        def make(robot_name: str) -> Backend:
            robot = load_robot(robot_name)
            chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud=robot.bus.baud)
            for servo in chain.servos:
                servo.poke("return_delay_time", 0)
            url = stack.enter_context(registered(chain))
            return DynamixelBackend(
                robot, port=url, port_handler_factory=EmulatedPortHandler,
                clock=lambda: chain.now_s, sleep=chain.advance,
            )

        yield make


FACTORIES["dynamixel"] = _dynamixel_factory


@pytest.fixture(params=sorted(FACTORIES))
def make_backend(request: pytest.FixtureRequest) -> Iterator[BackendFactory]:
    """A factory for the backend under test (one parametrisation per backend)."""
    yield from FACTORIES[request.param]()
