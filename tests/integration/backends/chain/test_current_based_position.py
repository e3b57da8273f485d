"""Current-based position control (Operating Mode 5) on an XM430 chain, through the real
dynamixel_sdk over the emulator: a torque cap becomes each servo's Goal Current before torque
comes on, servos not in mode 5 are refused by ID, and models without the mode do not offer it."""

from __future__ import annotations

import warnings
from collections.abc import Iterator

import numpy as np
import pytest

from snakebot.backends.capabilities import LimitsTorque
from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.backends.chain.faults import ServoSettingsError, ServoSettingsWarning
from snakebot.config import load_robot
from snakebot.config.schema import RobotConfig
from snakebot.emulation import EmulatedChain, make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.servo_tables import table_for_model

BAUD = 1_000_000


@pytest.fixture
def robot() -> RobotConfig:
    return load_robot("snake8-xm430")


@pytest.fixture
def chain(robot: RobotConfig) -> Iterator[tuple[EmulatedChain, str]]:
    """snake8-xm430's eight XM430-W350 servos as `snakebot config apply` leaves them (mode 5)."""
    emulated = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud=BAUD)
    for servo in emulated.servos:
        servo.poke("return_delay_time", 0)
        servo.poke("operating_mode", 5)
    with registered(emulated) as url:
        yield emulated, url


def _backend(robot: RobotConfig, chain: EmulatedChain, url: str) -> ServoChainBackend:
    return ServoChainBackend(
        robot,
        port=url,
        baud=BAUD,
        port_handler_factory=EmulatedPortHandler,
        clock=lambda: chain.now_s,
        sleep=chain.advance,
    )


def _goal_current_nm(chain: EmulatedChain, robot: RobotConfig) -> list[float]:
    """Each servo's Goal Current as the torque it allows, N*m (kt = stall torque / current)."""
    table = table_for_model(robot.servo.name)
    kt = robot.servo.physics.stall_torque_nm / table.specs.stall_current_a
    return [s.peek("goal_current") * table["goal_current"].scale * kt for s in chain.servos]


def test_the_cap_is_each_servos_goal_current_before_torque_comes_on(
    robot: RobotConfig, chain: tuple[EmulatedChain, str]
) -> None:
    emulated, url = chain
    backend = _backend(robot, emulated, url)
    assert isinstance(backend, LimitsTorque)
    caps = np.linspace(0.5, 1.2, 8)
    backend.limit_torque(caps)
    seen: list[tuple[bool, int]] = []
    original = backend._set_gains  # runs after the cap is written, before torque comes on

    def spy(gains: object) -> None:
        servo = emulated.servos[0]
        seen.append((servo.torque_enabled, servo.peek("goal_current")))
        original(gains)  # type: ignore[arg-type]

    backend._set_gains = spy  # type: ignore[method-assign]
    with pytest.warns(ServoSettingsWarning, match="ignore their Min/Max Position Limit"):
        backend.connect()
    try:
        limits = [s.peek("current_limit") for s in emulated.servos]
        assert seen and seen[0][0] is False and seen[0][1] < limits[0]
        tick = table_for_model(robot.servo.name)["goal_current"].scale
        kt = (
            robot.servo.physics.stall_torque_nm
            / table_for_model(robot.servo.name).specs.stall_current_a
        )
        np.testing.assert_allclose(_goal_current_nm(emulated, robot), caps, atol=tick * kt)
        assert all(s.torque_enabled for s in emulated.servos)
        # After connect a new cap is written at once; one above stall is the Current Limit.
        backend.limit_torque(2 * robot.servo.physics.stall_torque_nm)
        assert [s.peek("goal_current") for s in emulated.servos] == limits
    finally:
        backend.close()


def test_servos_not_in_current_based_position_are_refused_by_id_with_torque_off(
    robot: RobotConfig, chain: tuple[EmulatedChain, str]
) -> None:
    emulated, url = chain
    emulated.servo(3).poke("operating_mode", 3)
    emulated.servo(6).poke("operating_mode", 3)
    backend = _backend(robot, emulated, url)
    backend.limit_torque(1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ServoSettingsWarning)
        with pytest.raises(ServoSettingsError) as info:
            backend.connect()
    problems = info.value.problems
    assert [p.split(":")[0] for p in problems] == ["servo 3", "servo 6"]
    assert "Operating Mode is 3" in problems[0] and "needs 5" in problems[0]
    assert "operating_mode = 5" in problems[0]
    assert not any(s.torque_enabled for s in emulated.servos)


def test_without_a_cap_mode_5_runs_as_position_control_at_the_current_limit(
    robot: RobotConfig, chain: tuple[EmulatedChain, str]
) -> None:
    emulated, url = chain
    backend = _backend(robot, emulated, url)
    with pytest.warns(ServoSettingsWarning, match="Operating Mode 5"):
        backend.connect()
    try:
        assert [s.peek("goal_current") for s in emulated.servos] == [
            s.peek("current_limit") for s in emulated.servos
        ]
        assert backend.torque_enabled
    finally:
        backend.close()


@pytest.mark.parametrize("model", ["XL430-W250", "AX-12A", "STS3215"])
def test_models_without_current_based_position_do_not_offer_a_cap(model: str) -> None:
    robot = {"XL430-W250": "snake8", "AX-12A": "snake12-ax12a", "STS3215": "snake12-sts3215"}
    config = load_robot(robot[model])
    emulated = make_chain_for_ids(config.servo.name, config.servo_ids, baud=config.bus.baud)
    with registered(emulated) as url:
        backend = ServoChainBackend(
            config, port=url, baud=config.bus.baud, port_handler_factory=EmulatedPortHandler
        )
        assert not isinstance(backend, LimitsTorque)
