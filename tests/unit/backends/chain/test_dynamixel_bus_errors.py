"""SDK result codes to typed errors, retries and the SDK traps, over a scripted port."""

from __future__ import annotations

import os

import numpy as np
import pytest

from snakebot.backends.chain.bus import ServoBus
from snakebot.backends.chain.faults import ServoStatusError, SyncReadError
from snakebot.backends.dynamixel.sdk import SdkLink, SyncWriter
from snakebot.errors import BusError
from snakebot.families import family_named
from snakebot.servo_tables import RegisterValueError
from tests.unit.backends.chain.fakeport import ScriptedPort, corrupt, fast_status, status

PING_XL430 = bytes([0x24, 0x04, 0x2E])  # model 1060, firmware 46


def le(value: int, size: int) -> bytes:
    return value.to_bytes(size, "little", signed=True)


@pytest.fixture
def port() -> ScriptedPort:
    return ScriptedPort("fake0")


@pytest.fixture
def bus(port: ScriptedPort) -> ServoBus:
    bus = ServoBus("fake0", 1_000_000, port_handler_factory=lambda name: port)
    bus.open()
    return bus


def test_ping_returns_the_model_number(bus: ServoBus, port: ScriptedPort) -> None:
    port.script = [status(1, 0, PING_XL430)]
    assert bus.ping(1) == 1060
    assert port.written[0] == bytes.fromhex("FF FF FD 00 01 03 00 01 19 4E")


def test_silent_servo_is_retried_then_named(bus: ServoBus, port: ScriptedPort) -> None:
    port.script = [None, None, None]
    with pytest.raises(BusError) as info:
        bus.read(5, "present_position")
    assert info.value.port == "fake0"
    assert info.value.servo_ids == (5,)
    assert "[TxRxResult] There is no status packet!" in str(info.value)
    assert "after 3 attempts" in str(info.value)
    assert len(port.written) == 3
    assert bus.retry_counts[5] == 2


def test_corrupt_reply_is_retried(bus: ServoBus, port: ScriptedPort) -> None:
    port.script = [corrupt(status(2, 0, le(-300, 4))), status(2, 0, le(-300, 4))]
    assert bus.read(2, "present_position") == -300
    assert bus.retry_counts == {2: 1}


def test_retries_are_bounded_by_the_setting(port: ScriptedPort) -> None:
    bus = ServoBus("fake0", 1_000_000, port_handler_factory=lambda n: port, retries=0)
    bus.open()
    port.script = [corrupt(status(2, 0, le(1, 4))), status(2, 0, le(1, 4))]
    with pytest.raises(BusError, match=r"Incorrect status packet.*after 1 attempt\)"):
        bus.read(2, "present_position")


def test_status_error_byte_becomes_a_typed_error(bus: ServoBus, port: ScriptedPort) -> None:
    port.script = [status(3, 0x04)]
    with pytest.raises(ServoStatusError) as info:
        bus.write(3, "position_p_gain", 900)
    assert info.value.error_byte == 0x04
    assert info.value.servo_ids == (3,)
    assert "[RxPacketError] The data value is out of range!" in str(info.value)
    assert len(port.written) == 1  # not retried


def test_eeprom_access_error_says_torque_must_be_off(bus: ServoBus, port: ScriptedPort) -> None:
    port.script = [status(3, 0x07)]
    with pytest.raises(ServoStatusError, match="only be written with torque off"):
        bus.write(3, "operating_mode", 3)


def test_instruction_crc_error_is_resent(bus: ServoBus, port: ScriptedPort) -> None:
    port.script = [status(3, 0x03), status(3, 0)]
    bus.write(3, "led", 1)
    assert len(port.written) == 2
    assert port.written[0] == port.written[1]


def test_alert_bit_keeps_the_data_and_flags_the_servo(bus: ServoBus, port: ScriptedPort) -> None:
    port.script = [status(4, 0x80, bytes([0x20]))]
    assert bus.read(4, "hardware_error_status") == 0x20
    assert bus.alerts == {4}
    port.script = [status(4, 0)]
    bus.reboot(4)
    assert bus.alerts == set()


def test_values_out_of_register_range_never_reach_the_bus(
    bus: ServoBus, port: ScriptedPort
) -> None:
    with pytest.raises(RegisterValueError, match="position_p_gain = 20000"):
        bus.write(1, "position_p_gain", 20000)
    with pytest.raises(RegisterValueError, match="read-only"):
        bus.sync_write("present_position", {1: 0})
    assert port.written == []


def test_short_sync_write_rows_are_refused_before_add_param(port: ScriptedPort) -> None:
    link = SdkLink(port, family_named("dynamixel-p2"))
    with pytest.raises(ValueError, match="servo 2: 3 data bytes, register needs 4"):
        SyncWriter(link, 116, 4, [(1, b"\x00\x08\x00\x00"), (2, b"\x00\x08\x00")])


def test_sync_write_plan_sends_the_reference_packet(bus: ServoBus, port: ScriptedPort) -> None:
    # reference/dynamixel.md §1.9: Sync Write 116/4, ID1=150, ID2=170
    plan = bus.sync_write_plan("goal_position", [1, 2])
    plan.write(np.array([150, 170]))
    assert port.written[-1] == bytes.fromhex(
        "FF FF FD 00 FE 11 00 83 74 00 04 00 01 96 00 00 00 02 AA 00 00 00 82 87"
    )
    with pytest.raises(RegisterValueError):
        plan.write(np.array([150, 2_000_000]))
    with pytest.raises(ValueError, match="need 2 integers"):
        plan.write(np.array([1.5, 2.0]))
    with pytest.raises(RegisterValueError):
        plan.write([150, 2**40], checked=False)  # packing still refuses what cannot fit


def test_exception_mid_transaction_does_not_leave_the_port_busy(
    bus: ServoBus, port: ScriptedPort
) -> None:
    port.script = [status(1, 0, le(7, 4))]
    port.fail_on_read = OSError(5, "Input/output error")
    with pytest.raises(BusError, match="the serial port vanished or failed"):
        bus.read(1, "present_position")
    assert port.is_using is False
    port.fail_on_read = KeyboardInterrupt()
    port.script = [status(1, 0, le(7, 4))]
    with pytest.raises(KeyboardInterrupt):
        bus.read(1, "present_position")
    assert port.is_using is False
    port.fail_on_read = None
    port.script = [status(1, 0, le(7, 4))]
    assert bus.read(1, "present_position") == 7


def test_interrupted_group_read_does_not_leave_the_port_busy(
    bus: ServoBus, port: ScriptedPort
) -> None:
    port.script = [status(1, 0, block(0, 0, 5))]
    port.fail_on_read = KeyboardInterrupt()
    with pytest.raises(KeyboardInterrupt):
        bus.sync_read_plan(KEYS, [1]).read_rows(fast=False)
    assert port.is_using is False


def test_a_stuck_busy_flag_is_cleared(bus: ServoBus, port: ScriptedPort) -> None:
    port.is_using = True  # as a crashed earlier transaction would leave it
    port.script = [status(1, 0, le(9, 4))]
    assert bus.read(1, "present_position") == 9


def block(load: int, velocity: int, position: int) -> bytes:
    return le(load, 2) + le(velocity, 4) + le(position, 4)


KEYS = ("present_load", "present_velocity", "present_position")


def test_sync_read_decodes_signed_values(bus: ServoBus, port: ScriptedPort) -> None:
    port.script = [status(1, 0, block(-5, -20, 1000)) + status(2, 0, block(300, 4, -4))]
    values = bus.sync_read(KEYS, [1, 2])
    assert values == {
        1: {"present_load": -5, "present_velocity": -20, "present_position": 1000},
        2: {"present_load": 300, "present_velocity": 4, "present_position": -4},
    }
    assert port.written[0][7] == 0x82 and port.written[0][8:12] == bytes([126, 0, 10, 0])


def test_one_missing_servo_never_publishes_zeros(bus: ServoBus, port: ScriptedPort) -> None:
    group = status(1, 0, block(1, 2, 2100)) + status(3, 0, block(3, 4, 1900))  # 2 is silent
    port.script = [
        group,
        group,
        group,
        status(1, 0, block(1, 2, 2101)),
        None,
        None,
        None,
        status(3, 0, block(3, 4, 1901)),
    ]
    with pytest.raises(SyncReadError) as info:
        bus.sync_read(KEYS, [1, 2, 3])
    error = info.value
    assert error.missing_ids == (2,) and error.servo_ids == (2,)
    assert "servo(s) 2 after 3 attempts" in str(error)
    assert error.partial[1]["present_position"] == 2101
    assert error.partial[3]["present_position"] == 1901
    assert 2 not in error.partial
    assert bus.group_retries == 2
    assert bus.retry_counts == {2: 2}


def test_records_fall_back_to_single_reads_when_every_servo_answers_alone(
    bus: ServoBus, port: ScriptedPort
) -> None:
    port.script = [
        None,
        None,
        None,
        status(1, 0, block(1, -2, 2100)),
        status(2, 0, block(3, 4, 1900)),
    ]
    plan = bus.sync_read_plan(KEYS, [1, 2])
    rows = plan.read_rows(fast=True)
    assert rows == [(1, -2, 2100), (3, 4, 1900)]
    assert bus.group_fallbacks == 1


def test_transient_group_failure_is_retried(bus: ServoBus, port: ScriptedPort) -> None:
    good = status(1, 0, block(0, 0, 2048)) + status(2, 0, block(0, 0, 2049))
    port.script = [corrupt(good), good]
    rows = bus.sync_read_plan(KEYS, [1, 2]).read_rows()
    assert [row[2] for row in rows] == [2048, 2049]
    assert bus.group_retries == 1 and bus.group_fallbacks == 0


def test_fast_sync_read_decodes_the_combined_reply(bus: ServoBus, port: ScriptedPort) -> None:
    port.script = [fast_status([(1, block(-1, 5, 2000)), (2, block(2, -5, 2100))])]
    rows = bus.sync_read_plan(KEYS, [1, 2]).read_rows(fast=True)
    assert rows == [(-1, 5, 2000), (2, -5, 2100)]
    assert port.written[0][7] == 0x8A


def test_short_fast_reply_is_retried_not_an_index_error(bus: ServoBus, port: ScriptedPort) -> None:
    short = fast_status([(1, block(0, 0, 2000))])  # valid CRC, servo 2's segment missing
    full = fast_status([(1, block(0, 0, 2000)), (2, block(0, 0, 2100))])
    port.script = [short, full]
    rows = bus.sync_read_plan(KEYS, [1, 2]).read_rows(fast=True)
    assert [row[2] for row in rows] == [2000, 2100]
    assert bus.group_retries == 1
    assert port.is_using is False


def test_a_missing_port_says_what_to_check() -> None:
    bus = ServoBus("/dev/ttyUSB-snakebot-missing", 1_000_000)  # the SDK's own PortHandler
    with pytest.raises(BusError, match=r"cannot open the port.*/dev/serial/by-id"):
        bus.open()


def test_a_baud_the_sdk_refuses_is_named() -> None:
    bus = ServoBus("/dev/ttyUSB-snakebot-missing", 4_500_000)
    with pytest.raises(BusError, match="refuses 4500000 bit/s"):
        bus.open()


@pytest.mark.skipif(os.name != "posix", reason="termios is POSIX")
def test_a_termios_error_from_a_vanished_port_is_a_bus_error(
    bus: ServoBus, port: ScriptedPort
) -> None:
    import termios

    port.script = [status(1, 0, le(7, 4))]
    port.fail_on_read = termios.error(5, "Input/output error")  # pyserial's tcflush lets it out
    with pytest.raises(BusError, match="the serial port vanished or failed") as info:
        bus.read(1, "present_position")
    assert bus.vanished is info.value
    assert port.is_using is False
