"""The dxlemu:// pyserial port on its own: virtual bus clock, in-flight replies, URL errors."""

import time
from collections.abc import Iterator

import pytest
import serial

from snakebot.emulation import EmulatedChain, make_chain_for_ids, registered
from snakebot.emulation.protocol import Instruction, build_instruction, parse_packets

BAUD = 1_000_000
PING_1 = build_instruction(1, Instruction.PING)


@pytest.fixture
def chain() -> EmulatedChain:
    return make_chain_for_ids("XL430-W250", [1, 2], BAUD)


@pytest.fixture
def port(chain: EmulatedChain) -> Iterator[serial.SerialBase]:
    with registered(chain, "unit-dxlemu") as url:
        handle = serial.serial_for_url(url, baudrate=BAUD, timeout=0)
        yield handle
        handle.close()


def test_reply_arrives_after_return_delay_on_the_virtual_clock(
    port: serial.SerialBase, chain: EmulatedChain
) -> None:
    assert chain.baud == BAUD
    start = port.clock_ms()
    assert port.write(PING_1) == len(PING_1)
    data = port.read(100)
    assert parse_packets(data)[0].servo_id == 1
    elapsed_s = (port.clock_ms() - start) / 1000
    expected = (10 + 14) * 10e-6 + 500e-6 + chain.servo(1).processing_time_s
    assert elapsed_s == pytest.approx(expected, rel=1e-6)


def test_missing_reply_costs_virtual_not_real_time(port: serial.SerialBase) -> None:
    port.write(build_instruction(9, Instruction.PING))
    wall, start = time.perf_counter(), port.clock_ms()
    while port.clock_ms() - start < 1000:
        assert port.read(11) == b""
    assert time.perf_counter() - wall < 0.5


def test_reset_input_buffer_keeps_replies_still_on_the_wire(
    port: serial.SerialBase, chain: EmulatedChain
) -> None:
    chain.delay_replies(1, 0.05)
    port.write(PING_1)
    start = port.clock_ms()
    while port.clock_ms() - start < 40:
        assert port.read(14) == b""
    port.reset_input_buffer()
    while port.in_waiting == 0:
        pass
    assert parse_packets(port.read(14))[0].servo_id == 1


def test_changing_the_port_baud_changes_the_line(
    port: serial.SerialBase, chain: EmulatedChain
) -> None:
    port.baudrate = 57600
    assert chain.baud == 57600
    port.write(PING_1)
    start = port.clock_ms()
    while port.clock_ms() - start < 50:
        assert port.read(14) == b""


def test_blocking_read_waits_on_the_virtual_clock(port: serial.SerialBase) -> None:
    port.timeout = 0.1
    port.write(PING_1)
    assert len(port.read(14)) == 14
    start = port.clock_ms()
    assert port.read(1) == b""
    assert port.clock_ms() - start >= 100


def test_wall_clock_mode_waits_for_real_time(chain: EmulatedChain) -> None:
    chain.delay_replies(1, 0.02)
    with registered(chain, "unit-wall", time="wall") as url:
        handle = serial.serial_for_url(url, baudrate=BAUD, timeout=0)
        start = time.monotonic()
        handle.write(PING_1)
        data = b""
        while len(data) < 14 and time.monotonic() - start < 1.0:
            data += handle.read(14)
        assert time.monotonic() - start >= 0.02
        assert parse_packets(data)[0].servo_id == 1
        handle.close()


def test_bad_urls_explain_the_grammar(chain: EmulatedChain) -> None:
    with registered(chain, "unit-known"):
        with pytest.raises(serial.SerialException, match="unit-known"):
            serial.serial_for_url("dxlemu://unit-unknown")
        with pytest.raises(serial.SerialException, match=r"dxlemu://<name>"):
            serial.serial_for_url("dxlemu://unit-known?time=later")
        with pytest.raises(serial.SerialException, match="poll_ms"):
            serial.serial_for_url("dxlemu://unit-known?poll_ms=-1")
