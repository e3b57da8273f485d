"""AX-12A and MX-28 (Protocol 1.0 firmware) as the emulator serves them, through the stock SDK."""

from __future__ import annotations

from collections.abc import Iterator

import dynamixel_sdk as dxl
import pytest

from snakebot.emulation import EmulatedChain, make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.emulation.protocol1 import ErrorBit

BAUD = 1_000_000
TORQUE, GOAL, SPEED, TORQUE_LIMIT, PRESENT, PRESENT_SPEED, LOCK = 24, 30, 32, 34, 36, 38, 47
CW_LIMIT, CCW_LIMIT, MOVING = 6, 8, 46


@pytest.fixture
def ax() -> EmulatedChain:
    return make_chain_for_ids("AX-12A", [1, 2], BAUD)


@pytest.fixture
def bus(ax: EmulatedChain) -> Iterator[tuple[dxl.PortHandler, dxl.Protocol1PacketHandler]]:
    with registered(ax) as url:
        port = EmulatedPortHandler(url)
        assert port.openPort() and port.setBaudRate(BAUD)
        yield port, dxl.PacketHandler(1.0)
        port.closePort()


def test_ax_is_ten_bits_over_300_degrees_centred_at_512(ax: EmulatedChain, bus) -> None:
    port, ph = bus
    assert ph.ping(port, 1) == (12, dxl.COMM_SUCCESS, 0)
    assert ph.read2ByteTxRx(port, 1, PRESENT) == (512, dxl.COMM_SUCCESS, 0)
    assert ph.write1ByteTxRx(port, 1, TORQUE, 1) == (dxl.COMM_SUCCESS, 0)
    assert ph.write2ByteTxRx(port, 1, GOAL, 1023) == (dxl.COMM_SUCCESS, 0)
    ax.advance(2.0)
    assert ph.read2ByteTxRx(port, 1, PRESENT) == (1023, dxl.COMM_SUCCESS, 0)
    assert ax.servo(1).state.position_rad == pytest.approx(511 * 300 / 1024 * 3.14159265 / 180)
    # Past the 10-bit range: refused by range.
    assert ph.write2ByteTxRx(port, 1, GOAL, 1024) == (dxl.COMM_SUCCESS, ErrorBit.RANGE)


def test_goal_outside_the_angle_limits_sets_the_angle_limit_bit_and_does_not_move(
    ax: EmulatedChain, bus
) -> None:
    port, ph = bus
    assert ph.write2ByteTxRx(port, 2, CCW_LIMIT, 700) == (dxl.COMM_SUCCESS, 0)
    assert ph.write1ByteTxRx(port, 2, TORQUE, 1) == (dxl.COMM_SUCCESS, 0)
    assert ph.write2ByteTxRx(port, 2, GOAL, 800) == (dxl.COMM_SUCCESS, ErrorBit.ANGLE_LIMIT)
    ax.advance(1.0)
    assert ph.read2ByteTxRx(port, 2, PRESENT)[0] == 512


def test_moving_speed_limits_the_speed_and_present_speed_is_sign_magnitude(
    ax: EmulatedChain, bus
) -> None:
    port, ph = bus
    assert ph.write2ByteTxRx(port, 1, SPEED, 100) == (dxl.COMM_SUCCESS, 0)  # 11.1 rpm
    assert ph.write1ByteTxRx(port, 1, TORQUE, 1) == (dxl.COMM_SUCCESS, 0)
    assert ph.write2ByteTxRx(port, 1, GOAL, 312) == (dxl.COMM_SUCCESS, 0)
    ax.advance(0.1)
    assert ph.read2ByteTxRx(port, 1, PRESENT_SPEED)[0] == 1024 + 100  # bit 10: CW
    assert ph.read1ByteTxRx(port, 1, MOVING)[0] == 1
    moved = 512 - ph.read2ByteTxRx(port, 1, PRESENT)[0]
    assert moved == pytest.approx(100 * 0.011623893 * 0.1 / 0.005113269, abs=2)
    assert ph.write2ByteTxRx(port, 1, SPEED, 0) == (dxl.COMM_SUCCESS, 0)  # 0 = full speed
    assert ax.servo(1).command().max_velocity_rad_s == ax.servo(1).table.specs.no_load_speed_rad_s


def test_torque_limit_starts_at_max_torque_and_zero_leaves_the_output_free(
    ax: EmulatedChain, bus
) -> None:
    port, ph = bus
    assert ph.write2ByteTxRx(port, 1, 14, 600) == (dxl.COMM_SUCCESS, 0)  # Max Torque (EEPROM)
    ax.servo(1).reboot()
    assert ph.read2ByteTxRx(port, 1, TORQUE_LIMIT)[0] == 600
    assert ph.write2ByteTxRx(port, 1, TORQUE_LIMIT, 0) == (dxl.COMM_SUCCESS, 0)
    assert ph.write1ByteTxRx(port, 1, TORQUE, 1) == (dxl.COMM_SUCCESS, 0)
    assert not ax.servo(1).command().torque_enabled


def test_lock_keeps_the_eeprom_until_a_power_cycle(ax: EmulatedChain, bus) -> None:
    port, ph = bus
    assert ph.write1ByteTxRx(port, 1, LOCK, 1) == (dxl.COMM_SUCCESS, 0)
    assert ph.write1ByteTxRx(port, 1, 5, 0) == (dxl.COMM_SUCCESS, ErrorBit.RANGE)  # RDT
    assert ph.write1ByteTxRx(port, 1, LOCK, 0) == (dxl.COMM_SUCCESS, ErrorBit.RANGE)
    assert ph.write1ByteTxRx(port, 1, 25, 1) == (dxl.COMM_SUCCESS, 0)  # RAM still writable
    ax.servo(1).reboot()
    assert ph.write1ByteTxRx(port, 1, 5, 0) == (dxl.COMM_SUCCESS, 0)


def test_eeprom_is_writable_with_torque_on_and_wheel_mode_turns(ax: EmulatedChain, bus) -> None:
    port, ph = bus
    assert ph.write1ByteTxRx(port, 2, TORQUE, 1) == (dxl.COMM_SUCCESS, 0)
    assert ph.write2ByteTxRx(port, 2, CW_LIMIT, 0) == (dxl.COMM_SUCCESS, 0)
    assert ph.write2ByteTxRx(port, 2, CCW_LIMIT, 0) == (dxl.COMM_SUCCESS, 0)
    assert ph.write2ByteTxRx(port, 2, SPEED, 200) == (dxl.COMM_SUCCESS, 0)  # CCW
    ax.advance(0.2)
    assert ax.servo(2).state.velocity_rad_s == pytest.approx(200 * 0.011623893)
    assert ph.write2ByteTxRx(port, 2, SPEED, 1024 + 200) == (dxl.COMM_SUCCESS, 0)  # CW
    ax.advance(0.2)
    assert ax.servo(2).state.velocity_rad_s == pytest.approx(-200 * 0.011623893)


def test_an_ax_ignores_bulk_read(ax: EmulatedChain, bus) -> None:
    port, ph = bus
    reader = dxl.GroupBulkRead(port, ph)
    assert reader.addParam(1, PRESENT, 2)
    reader.makeParam()
    # GroupBulkRead.txPacket passes the SDK 4.1 Protocol 1.0 handler one argument too many
    # (TypeError); the handler's own bulkReadTx is the same packet.
    assert ph.bulkReadTx(port, reader.param, 3) == dxl.COMM_SUCCESS
    assert reader.rxPacket() == dxl.COMM_RX_TIMEOUT


def test_overload_shuts_down_and_rides_on_the_status_until_torque_on() -> None:
    chain = make_chain_for_ids("AX-12A", [4], BAUD)
    servo = chain.servo(4)
    servo.poke("torque_enable", 1)
    chain.latch_hardware_error(4, 0x20)
    assert not servo.torque_enabled
    with registered(chain) as url:
        port = EmulatedPortHandler(url)
        assert port.openPort() and port.setBaudRate(BAUD)
        ph = dxl.PacketHandler(1.0)
        assert ph.ping(port, 4) == (12, dxl.COMM_SUCCESS, ErrorBit.OVERLOAD)
        assert ph.write1ByteTxRx(port, 4, TORQUE, 1) == (dxl.COMM_SUCCESS, 0)
        assert ph.ping(port, 4) == (12, dxl.COMM_SUCCESS, 0) and servo.torque_enabled
        port.closePort()


def test_mx28_p1_gains_at_26_27_28_and_bulk_read() -> None:
    chain = make_chain_for_ids("MX-28", [1, 2], 57600)
    with registered(chain) as url:
        port = EmulatedPortHandler(url)
        assert port.openPort() and port.setBaudRate(57600)
        ph = dxl.PacketHandler(1.0)
        assert ph.ping(port, 2) == (29, dxl.COMM_SUCCESS, 0)
        assert [ph.read1ByteTxRx(port, 1, a)[0] for a in (26, 27, 28)] == [0, 0, 32]
        assert ph.write1ByteTxRx(port, 1, 28, 50) == (dxl.COMM_SUCCESS, 0)
        assert chain.servo(1).command().position_gains == (50, 0, 0)
        reader = dxl.GroupBulkRead(port, ph)
        assert reader.addParam(1, PRESENT, 2) and reader.addParam(2, MOVING, 1)
        reader.makeParam()
        assert ph.bulkReadTx(port, reader.param, 6) == dxl.COMM_SUCCESS
        assert reader.rxPacket() == dxl.COMM_SUCCESS
        assert (reader.getData(1, PRESENT, 2), reader.getData(2, MOVING, 1)) == (2048, 0)
        port.closePort()
