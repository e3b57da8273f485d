"""A 2XL430-W250 on the emulated bus is two axes in one case, through the stock SDK (dxlemu://):
one communication module holds the baud rate and protocol for both, the axes cannot share an ID,
and EEPROM waits for torque off on both (e-Manual 2XL430-W250 control table notes)."""

from __future__ import annotations

from collections.abc import Iterator

import dynamixel_sdk as sdk
import pytest

from snakebot.config import load_robot
from snakebot.emulation import EmulatedChain, EmulationError, make_chain_for_ids, registered
from snakebot.emulation.bench import robot_servos
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.servo_tables import table_for_model

MODEL = "2XL430-W250"
BAUD = 57_600
ID, BAUD_RATE, RETURN_DELAY, PROTOCOL, TORQUE = 7, 8, 9, 13, 64
DATA_LIMIT, ACCESS = 0x06, 0x07


class Bus:
    """The SDK's port and Protocol 2.0 handler on one emulated chain."""

    def __init__(self, chain: EmulatedChain, port: EmulatedPortHandler) -> None:
        self.chain, self.port, self.packet = chain, port, sdk.PacketHandler(2.0)

    def ping(self, servo_id: int) -> int | None:
        model, result, _ = self.packet.ping(self.port, servo_id)
        return int(model) if result == sdk.COMM_SUCCESS else None

    def write1(self, servo_id: int, address: int, value: int) -> int:
        """The status packet's error number (0 = done); fails the test on a bus error."""
        result, error = self.packet.write1ByteTxRx(self.port, servo_id, address, value)
        assert result == sdk.COMM_SUCCESS, self.packet.getTxRxResult(result)
        return int(error)

    def read1(self, servo_id: int, address: int) -> int:
        value, result, _ = self.packet.read1ByteTxRx(self.port, servo_id, address)
        assert result == sdk.COMM_SUCCESS, self.packet.getTxRxResult(result)
        return int(value)


@pytest.fixture
def bus() -> Iterator[Bus]:
    chain = make_chain_for_ids(MODEL, [1, 2, 3, 4], BAUD)  # two cases: 1-2 and 3-4
    with registered(chain, "two-xl430") as url:
        port = EmulatedPortHandler(url)
        assert port.openPort() and port.setBaudRate(BAUD)
        yield Bus(chain, port)
        port.closePort()


def test_every_axis_answers_with_its_own_id_and_the_model_number(bus: Bus) -> None:
    assert [bus.ping(i) for i in (1, 2, 3, 4)] == [1090] * 4


def test_a_baud_rate_written_to_one_axis_moves_its_case_and_not_the_next(bus: Bus) -> None:
    index_1m = table_for_model(MODEL).baud_index(1_000_000)
    assert bus.write1(1, BAUD_RATE, index_1m) == 0
    assert bus.ping(2) is None and bus.ping(3) == 1090  # axis 2 went along; case 3-4 stayed
    bus.port.setBaudRate(1_000_000)
    assert bus.ping(1) == bus.ping(2) == 1090
    assert bus.read1(2, BAUD_RATE) == index_1m
    assert bus.ping(3) is None


def test_protocol_type_written_to_one_axis_switches_both(bus: Bus) -> None:
    assert bus.write1(2, PROTOCOL, 1) == 0
    assert bus.ping(1) is None and bus.ping(2) is None  # both now speak Protocol 1.0 only
    assert [s.peek("protocol_type") for s in bus.chain.servos] == [1, 1, 2, 2]


def test_an_axis_cannot_take_the_id_of_the_other_axis(bus: Bus) -> None:
    assert bus.write1(2, ID, 1) == DATA_LIMIT
    assert bus.ping(2) == 1090  # nothing was set
    assert bus.write1(2, ID, 9) == 0  # any other ID is the user's choice
    assert bus.ping(9) == 1090 and bus.ping(2) is None


def test_eeprom_waits_for_torque_off_on_both_axes(bus: Bus) -> None:
    assert bus.write1(2, TORQUE, 1) == 0
    assert bus.write1(1, RETURN_DELAY, 0) == ACCESS  # the other axis holds torque
    assert bus.write1(3, RETURN_DELAY, 0) == 0  # another case is not concerned
    assert bus.write1(2, TORQUE, 0) == 0
    assert bus.write1(1, RETURN_DELAY, 0) == 0
    assert bus.read1(1, RETURN_DELAY) == 0 and bus.read1(2, RETURN_DELAY) == 250


def test_a_factory_reset_of_one_axis_resets_the_baud_of_both(bus: Bus) -> None:
    factory = bus.read1(1, BAUD_RATE)
    servo_1, servo_2 = bus.chain.servo(1), bus.chain.servo(2)
    for servo in (servo_1, servo_2):
        servo.poke("baud_rate", table_for_model(MODEL).baud_index(1_000_000))
    bus.port.setBaudRate(1_000_000)
    result, _ = bus.packet.factoryReset(bus.port, 1, 0x01)  # all but the ID
    assert result == sdk.COMM_SUCCESS
    assert servo_1.peek("baud_rate") == servo_2.peek("baud_rate") == factory


def test_unplugging_one_axis_takes_its_whole_case_off_the_bus(bus: Bus) -> None:
    bus.chain.silence(1)
    assert [bus.ping(i) for i in (1, 2, 3, 4)] == [None, None, 1090, 1090]


def test_ids_that_leave_a_case_incomplete_are_refused_naming_the_model() -> None:
    with pytest.raises(EmulationError, match="2XL430-W250 has 2 axes"):
        make_chain_for_ids(MODEL, [1, 2, 3], BAUD)
    with pytest.raises(EmulationError, match="whole cases"):
        robot_servos(MODEL, [1, 2, 3, 4, 5], BAUD)


def test_single_axis_models_form_no_cases() -> None:
    chain = make_chain_for_ids("XL430-W250", [1, 1], BAUD)
    assert all(servo.case is None for servo in chain.servos)


def test_the_shipped_2xl430_robot_is_served_as_four_cases() -> None:
    robot = load_robot("snake8-2xl430")
    servos = robot_servos(robot.servo.name, robot.servo_ids, BAUD)
    cases = [[axis.servo_id for axis in s.case.axes] for s in servos[::2] if s.case is not None]
    assert cases == [[1, 2], [3, 4], [5, 6], [7, 8]]
