"""The conformance suite every backend passes (snakebot.testing.BackendContract, DESIGN.md "The
backend contract"), run here on the built-in backends, each made through the backend registry."""

from __future__ import annotations

import contextlib
import tempfile
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import pytest

from snakebot.backends import claimed
from snakebot.backends.base import Backend
from snakebot.backends.registry import make_backend
from snakebot.config import RobotConfig, load_robot
from snakebot.config.body_loader import load_body
from snakebot.emulation import make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.testing import BackendContract, RobotFactory


class TestTwin(BackendContract):
    time_tolerance_s = 1e-9  # simulated time: exact

    def make(self, robot: RobotConfig) -> Backend:
        # Frictionless ground: the contract checks the servo loop, not locomotion.
        return make_backend(robot, "twin", friction="0,0")


class TestSoftBody(BackendContract):
    time_tolerance_s = 1e-9  # simulated time: exact

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


def _metered(robot: RobotConfig) -> RobotConfig:
    """``robot`` whose servo file gives the twin the stall current (an XL430's 1.3 A), so the
    twin models each servo's current draw."""
    physics = robot.servo.physics
    extras = replace(physics.extras, stall_current_a=1.3)
    return replace(robot, servo=replace(robot.servo, physics=replace(physics, extras=extras)))


class TestTwinWithCurrent(BackendContract):
    """The twin of a servo file that models current: it senses current as well."""

    time_tolerance_s = 1e-9

    def make(self, robot: RobotConfig) -> Backend:
        return make_backend(_metered(robot), "twin", friction="0,0")


class TestDynamixelXM430(BackendContract):
    """An XM430 chain over the emulator, set up for current-based position control (Operating
    Mode 5): the model reports Present Current, so the backend senses current and torque, and
    can cap its torque; on the emulator's virtual clock."""

    @contextlib.contextmanager
    def backends(self) -> Iterator[RobotFactory]:
        with contextlib.ExitStack() as stack:
            folder = Path(stack.enter_context(tempfile.TemporaryDirectory()))

            def make(robot: RobotConfig) -> Backend:
                path = folder / Path(robot.source).name
                text = Path(robot.source).read_text(encoding="utf-8")
                path.write_text(text.replace('"XL430-W250"', '"XM430-W350"'), encoding="utf-8")
                robot = load_robot(path)
                assert robot.servo.name == "XM430-W350"
                chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud=robot.bus.baud)
                for servo in chain.servos:
                    servo.poke("operating_mode", 5)  # as `snakebot config apply` leaves them
                url = stack.enter_context(registered(chain))
                return make_backend(
                    robot, "dynamixel", port=url, port_handler_factory=EmulatedPortHandler,
                    clock=lambda: chain.now_s, sleep=chain.advance,
                )  # fmt: skip

            yield make


@pytest.mark.parametrize(
    ("case", "abilities"),
    [
        (
            TestTwin,
            (
                "SensesBody",
                "SensesImu",
                "ChecksPhysics",
                "SensesTorque",
                "LimitsTorque",
                "Resettable",
                "Simulated",
            ),
        ),
        (
            TestTwinWithCurrent,
            (
                "SensesBody",
                "SensesImu",
                "ChecksPhysics",
                "SensesCurrent",
                "SensesTorque",
                "LimitsTorque",
                "Resettable",
                "Simulated",
            ),
        ),
        (TestSoftBody, ("SensesBody", "ChecksPhysics", "ReportsTravel", "Simulated")),
        (TestDynamixel, ("ReportsHealth", "OnBus")),
        (
            TestDynamixelXM430,
            ("ReportsHealth", "SensesCurrent", "SensesTorque", "LimitsTorque", "OnBus"),
        ),
    ],
)
def test_each_backend_claims_what_it_has(
    case: type[BackendContract], abilities: tuple[str, ...]
) -> None:
    """What each built-in backend declares (and so what the contract above holds it to); all
    but Simulated before connect already (the MuJoCo model is built at connect)."""
    with case().backends() as factory:
        backend = factory(load_robot("snake8"))
        assert claimed(backend) == tuple(a for a in abilities if a != "Simulated")
        with backend:
            assert claimed(backend) == abilities
