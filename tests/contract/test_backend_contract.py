"""The conformance suite every backend passes (snakebot.testing.BackendContract, DESIGN.md "The
backend contract"), run here on the built-in backends, each made through the backend registry."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from dataclasses import replace

from snakebot.backends.base import Backend
from snakebot.backends.registry import make_backend
from snakebot.config import RobotConfig
from snakebot.config.body_loader import load_body
from snakebot.emulation import make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.testing import BackendContract, RobotFactory


class TestTwin(BackendContract):
    def make(self, robot: RobotConfig) -> Backend:
        # Frictionless ground: the contract checks the servo loop, not locomotion.
        return make_backend(robot, "twin", friction="0,0")


class TestSoftBody(BackendContract):
    def make(self, robot: RobotConfig) -> Backend:
        """Miller's snake lattice with one yaw muscle channel per joint of ``robot``."""
        body = load_body("snake")
        body = replace(
            body,
            lattice=replace(body.lattice, segments=robot.joint_count),
            muscles=replace(body.muscles, channels=("yaw",)),
        )
        return make_backend(body, "softbody", friction=0.0)


class TestDynamixel(BackendContract):
    """The real dynamixel_sdk over the in-process emulator; the bus clock is the backend's."""

    @contextlib.contextmanager
    def backends(self) -> Iterator[RobotFactory]:
        with contextlib.ExitStack() as stack:

            def make(robot: RobotConfig) -> Backend:
                chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud=robot.bus.baud)
                for servo in chain.servos:
                    servo.poke("return_delay_time", 0)
                url = stack.enter_context(registered(chain))
                return make_backend(
                    robot, "dynamixel", port=url, port_handler_factory=EmulatedPortHandler,
                    clock=lambda: chain.now_s, sleep=chain.advance,
                )  # fmt: skip

            yield make
