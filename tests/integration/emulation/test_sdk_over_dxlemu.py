"""The unmodified dynamixel_sdk talking to the emulated bus through dxlemu:// (in-process)."""

import time

import dynamixel_sdk as dxl
import pytest

from snakebot.emulation import (
    EmulatedChain,
    HardwareError,
    VirtualServo,
    make_chain_for_ids,
    registered,
)
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.servo_tables import decode_signed

Port = EmulatedPortHandler
PH = dxl.Protocol2PacketHandler
GOAL, PRESENT, TORQUE, LED = 116, 132, 64, 65
BAUD = 1_000_000  # as in conftest.py
IDS = list(range(1, 13))


def torque_on(port: Port, ph: PH, ids: list[int]) -> None:
    for servo_id in ids:
        assert ph.write1ByteTxRx(port, servo_id, TORQUE, 1) == (dxl.COMM_SUCCESS, 0)


def test_ping_and_absent_id(port: Port, packet_handler: PH) -> None:
    assert packet_handler.ping(port, 5) == (1020, dxl.COMM_SUCCESS, 0)
    wall = time.perf_counter()
    assert packet_handler.ping(port, 42)[1] == dxl.COMM_RX_TIMEOUT
    assert time.perf_counter() - wall < 0.5


def test_broadcast_ping_finds_all_twelve(port: Port, packet_handler: PH) -> None:
    found, result = packet_handler.broadcastPing(port)
    assert result == dxl.COMM_SUCCESS
    assert found == {servo_id: [1020, 46] for servo_id in IDS}


def test_read_and_write_one_two_and_four_bytes(port: Port, packet_handler: PH) -> None:
    ph = packet_handler
    assert ph.write1ByteTxRx(port, 3, LED, 1) == (dxl.COMM_SUCCESS, 0)
    assert ph.read1ByteTxRx(port, 3, LED) == (1, dxl.COMM_SUCCESS, 0)
    assert ph.write2ByteTxRx(port, 3, 84, 1234) == (dxl.COMM_SUCCESS, 0)
    assert ph.read2ByteTxRx(port, 3, 84) == (1234, dxl.COMM_SUCCESS, 0)
    assert ph.write4ByteTxRx(port, 3, GOAL, 3000) == (dxl.COMM_SUCCESS, 0)
    assert ph.read4ByteTxRx(port, 3, GOAL) == (3000, dxl.COMM_SUCCESS, 0)
    assert ph.read4ByteTxRx(port, 3, PRESENT) == (2048, dxl.COMM_SUCCESS, 0)


def test_error_byte_reaches_the_sdk(port: Port, packet_handler: PH) -> None:
    torque_on(port, packet_handler, [2])
    result, error = packet_handler.write1ByteTxRx(port, 2, 11, 1)  # Operating Mode is EEPROM
    assert (result, error) == (dxl.COMM_SUCCESS, 7)
    assert "not available" in packet_handler.getRxPacketError(error)
    result, error = packet_handler.write4ByteTxRx(port, 2, GOAL, 5000)
    assert error == 6


def test_sync_write_then_sync_read_after_motion(
    port: Port, packet_handler: PH, chain: EmulatedChain
) -> None:
    torque_on(port, packet_handler, IDS)
    writer = dxl.GroupSyncWrite(port, packet_handler, GOAL, 4)
    goals = {servo_id: 2048 + 50 * servo_id for servo_id in IDS}
    for servo_id, goal in goals.items():
        assert writer.addParam(servo_id, list(goal.to_bytes(4, "little")))
    assert writer.txPacket() == dxl.COMM_SUCCESS
    chain.advance(1.0)
    reader = dxl.GroupSyncRead(port, packet_handler, PRESENT, 4)
    for servo_id in IDS:
        assert reader.addParam(servo_id)
    assert reader.txRxPacket() == dxl.COMM_SUCCESS
    assert {i: reader.getData(i, PRESENT, 4) for i in IDS} == goals


def test_fast_sync_read_of_the_state_block(
    port: Port, packet_handler: PH, chain: EmulatedChain
) -> None:
    chain.servo(4).poke("drive_mode", 1)
    reader = dxl.GroupSyncRead(port, packet_handler, 126, 10)
    for servo_id in IDS:
        reader.addParam(servo_id)
    assert hasattr(reader, "fastSyncRead")
    assert reader.fastSyncRead() == dxl.COMM_SUCCESS
    positions = {i: decode_signed(reader.getData(i, PRESENT, 4), 4) for i in IDS}
    assert positions == dict.fromkeys(IDS, 2048)


def test_bulk_read_and_fast_bulk_read(port: Port, packet_handler: PH, chain: EmulatedChain) -> None:
    chain.servo(10).poke("goal_position", 777)
    reader = dxl.GroupBulkRead(port, packet_handler)
    assert (
        reader.addParam(10, GOAL, 4) and reader.addParam(11, 146, 1) and reader.addParam(12, 144, 2)
    )
    assert reader.txRxPacket() == dxl.COMM_SUCCESS
    values = (reader.getData(10, GOAL, 4), reader.getData(11, 146, 1), reader.getData(12, 144, 2))
    assert values == (777, 30, 120)
    assert reader.fastBulkRead() == dxl.COMM_SUCCESS
    assert (reader.getData(10, GOAL, 4), reader.getData(12, 144, 2)) == (777, 120)


def test_bulk_write(port: Port, packet_handler: PH, chain: EmulatedChain) -> None:
    writer = dxl.GroupBulkWrite(port, packet_handler)
    assert writer.addParam(1, LED, 1, [1]) and writer.addParam(2, GOAL, 4, [0, 4, 0, 0])
    assert writer.txPacket() == dxl.COMM_SUCCESS
    assert chain.servo(1).peek("led") == 1 and chain.servo(2).peek("goal_position") == 1024


def test_hardware_error_alert_and_reboot(
    port: Port, packet_handler: PH, chain: EmulatedChain
) -> None:
    torque_on(port, packet_handler, [6])
    chain.latch_hardware_error(6, HardwareError.OVERLOAD)
    status, result, error = packet_handler.read1ByteTxRx(port, 6, 70)
    assert (status, result, error) == (HardwareError.OVERLOAD, dxl.COMM_SUCCESS, 0x80)
    assert "Hardware error" in packet_handler.getRxPacketError(error)
    assert packet_handler.read1ByteTxRx(port, 6, TORQUE)[0] == 0
    assert packet_handler.reboot(port, 6) == (dxl.COMM_SUCCESS, 0x80)
    assert packet_handler.read1ByteTxRx(port, 6, 70) == (0, dxl.COMM_SUCCESS, 0)


def test_factory_reset_keeps_id_and_baud(
    port: Port, packet_handler: PH, chain: EmulatedChain
) -> None:
    assert packet_handler.write1ByteTxRx(port, 8, 9, 0) == (dxl.COMM_SUCCESS, 0)
    assert packet_handler.factoryReset(port, 8, 0x02) == (dxl.COMM_SUCCESS, 0)
    assert packet_handler.read1ByteTxRx(port, 8, 9) == (250, dxl.COMM_SUCCESS, 0)
    assert packet_handler.factoryReset(port, 8, 0xFF) == (dxl.COMM_SUCCESS, 0)
    assert packet_handler.ping(port, 8)[1] == dxl.COMM_RX_TIMEOUT  # now ID 1 at 57600
    assert len(chain.servos_with_id(1)) == 2 and chain.servos_with_id(1)[1].baud == 57600


def test_silenced_servo_times_out_alone_and_in_a_group(
    port: Port, packet_handler: PH, chain: EmulatedChain
) -> None:
    chain.silence(7)
    assert packet_handler.read4ByteTxRx(port, 7, PRESENT)[1] == dxl.COMM_RX_TIMEOUT
    reader = dxl.GroupSyncRead(port, packet_handler, PRESENT, 4)
    for servo_id in IDS:
        reader.addParam(servo_id)
    assert reader.txRxPacket() == dxl.COMM_RX_TIMEOUT
    chain.silence(7, False)
    assert reader.txRxPacket() == dxl.COMM_SUCCESS


def test_corrupted_dropped_and_late_replies(
    port: Port, packet_handler: PH, chain: EmulatedChain
) -> None:
    chain.corrupt_replies(3, next_n=1)
    assert packet_handler.ping(port, 3)[1] == dxl.COMM_RX_CORRUPT
    assert packet_handler.ping(port, 3)[1] == dxl.COMM_SUCCESS
    chain.drop_replies(3, next_n=1)
    assert packet_handler.ping(port, 3)[1] == dxl.COMM_RX_TIMEOUT
    chain.delay_replies(3, 0.020)
    assert packet_handler.ping(port, 3)[1] == dxl.COMM_SUCCESS
    chain.delay_replies(3, 0.100)
    assert packet_handler.ping(port, 3)[1] == dxl.COMM_RX_TIMEOUT


def test_bus_watchdog_through_the_sdk(port: Port, packet_handler: PH, chain: EmulatedChain) -> None:
    ph = packet_handler
    assert ph.write1ByteTxRx(port, 5, 98, 5) == (dxl.COMM_SUCCESS, 0)
    torque_on(port, ph, [5])
    chain.advance(0.2)
    assert ph.read1ByteTxRx(port, 5, 98) == (0xFF, dxl.COMM_SUCCESS, 0)
    assert ph.write4ByteTxRx(port, 5, GOAL, 2100) == (dxl.COMM_SUCCESS, 4)
    assert ph.write1ByteTxRx(port, 5, 98, 0) == (dxl.COMM_SUCCESS, 0)
    assert ph.write4ByteTxRx(port, 5, GOAL, 2100) == (dxl.COMM_SUCCESS, 0)


def test_wrong_port_baud_gets_silence(port: Port, packet_handler: PH) -> None:
    assert port.setBaudRate(57600)
    assert packet_handler.ping(port, 1)[1] == dxl.COMM_RX_TIMEOUT
    assert port.setBaudRate(BAUD)
    assert packet_handler.ping(port, 1)[1] == dxl.COMM_SUCCESS


def test_duplicate_ids_garble_the_reply(
    port: Port, packet_handler: PH, chain: EmulatedChain
) -> None:
    chain.add(VirtualServo("XM430-W350", 9, baud=BAUD, processing_time_s=3e-6))
    assert packet_handler.ping(port, 9)[1] in (dxl.COMM_RX_CORRUPT, dxl.COMM_RX_TIMEOUT)
    assert packet_handler.ping(port, 8)[1] == dxl.COMM_SUCCESS


def test_any_pyserial_url_opens() -> None:
    handler = EmulatedPortHandler("loop://")
    assert handler.openPort()
    # loop:// echoes the ping, which is no status packet: the SDK reports a corrupt reply.
    assert dxl.PacketHandler(2.0).ping(handler, 1)[1] == dxl.COMM_RX_CORRUPT
    handler.closePort()


@pytest.mark.parametrize("baud", [57600, 4_000_000])
def test_other_line_rates(baud: int) -> None:
    with registered(make_chain_for_ids("XL330-M288", [1, 2], baud)) as url:
        handler = EmulatedPortHandler(url)
        handler.baudrate = baud
        assert handler.openPort()
        assert dxl.PacketHandler(2.0).ping(handler, 2) == (1200, dxl.COMM_SUCCESS, 0)
        handler.closePort()


def test_duplicate_id_vanishes_from_a_broadcast_ping(
    port: Port, packet_handler: PH, chain: EmulatedChain
) -> None:
    chain.add(VirtualServo("XM430-W350", 2, baud=BAUD, processing_time_s=5e-6))
    found, result = packet_handler.broadcastPing(port)
    assert result == dxl.COMM_SUCCESS
    assert sorted(found) == [i for i in IDS if i != 2]  # the SDK skips the garbled slot


def test_fast_sync_read_too_long_for_one_packet_times_out_and_the_bus_lives_on(
    port: Port, packet_handler: PH
) -> None:
    reader = dxl.GroupSyncRead(port, packet_handler, 0, 1000)
    for servo_id in range(1, 71):
        reader.addParam(servo_id)
    assert reader.fastSyncRead() == dxl.COMM_RX_TIMEOUT
    assert packet_handler.ping(port, 7) == (1020, dxl.COMM_SUCCESS, 0)
