"""Protocol 1.0 instructions on emulated servos: who answers, with which error bits."""

import pytest

from snakebot.emulation import EmulatedChain, make_chain_for_ids
from snakebot.emulation.protocol1 import (
    BROADCAST_ID,
    ErrorBit,
    Instruction,
    build_instruction,
    parse_packets,
)
from snakebot.emulation.virtual_servo import VirtualServo

BAUD = 1_000_000


@pytest.fixture
def chain() -> EmulatedChain:
    """Three XL430s switched to Protocol 1.0 (Protocol Type 1), X control table."""
    chain = make_chain_for_ids("XL430-W250", [1, 2, 3], BAUD)
    for servo in chain.servos:
        servo.poke("protocol_type", 1)
    return chain


def send(chain: EmulatedChain, servo_id: int, instruction: int, params: bytes = b"") -> list:
    replies = chain.receive(build_instruction(servo_id, instruction, params))
    return [p for r in replies for p in parse_packets(r.data)]


def test_ping_gets_an_empty_status_and_x_servos_ignore_the_other_protocol(
    chain: EmulatedChain,
) -> None:
    (status,) = send(chain, 2, Instruction.PING)
    assert (status.servo_id, status.error, status.params) == (2, 0, b"")
    from snakebot.emulation import protocol

    assert chain.receive(protocol.build_instruction(2, protocol.Instruction.PING)) == []


def test_read_write_with_one_byte_addresses(chain: EmulatedChain) -> None:
    (status,) = send(chain, 1, Instruction.READ, bytes([0, 2]))
    assert int.from_bytes(status.params, "little") == 1060
    (status,) = send(chain, 1, Instruction.WRITE, bytes([65, 1]))  # LED
    assert status.error == 0 and chain.servo(1).peek("led") == 1


def test_error_bits_range_angle_limit_instruction_checksum(chain: EmulatedChain) -> None:
    servo = chain.servo(1)
    servo.poke("max_position_limit", 3000)
    (status,) = send(chain, 1, Instruction.WRITE, bytes([116]) + (3500).to_bytes(4, "little"))
    assert status.error == ErrorBit.ANGLE_LIMIT and servo.peek("goal_position") != 3500
    # One byte of a four-byte register: documented as a Range error (no ROBOTIS text).
    (status,) = send(chain, 1, Instruction.WRITE, bytes([116, 0x10]))
    assert status.error == ErrorBit.RANGE
    (status,) = send(chain, 1, Instruction.WRITE, bytes([11, 99]))  # Operating Mode 99
    assert status.error == ErrorBit.RANGE
    (status,) = send(chain, 1, 0x08)  # Reboot: not a Protocol 1.0 instruction
    assert status.error == ErrorBit.INSTRUCTION
    (status,) = send(chain, 1, 0x82, bytes([132, 4, 1]))  # Sync Read: neither
    assert status.error == ErrorBit.INSTRUCTION
    (status,) = send(chain, 1, Instruction.ACTION)  # nothing registered
    assert status.error == ErrorBit.INSTRUCTION
    broken = bytearray(build_instruction(1, Instruction.PING))
    broken[-1] ^= 0xFF
    (reply,) = chain.receive(bytes(broken))
    assert parse_packets(reply.data)[0].error == ErrorBit.CHECKSUM


def test_alarms_ride_on_every_status(chain: EmulatedChain) -> None:
    chain.latch_hardware_error(2, 0x20 | 0x04)
    (status,) = send(chain, 2, Instruction.PING)
    assert status.error == ErrorBit.OVERLOAD | ErrorBit.OVERHEATING


def test_no_status_to_broadcast_not_even_ping(chain: EmulatedChain) -> None:
    assert send(chain, BROADCAST_ID, Instruction.PING) == []
    assert send(chain, BROADCAST_ID, Instruction.WRITE, bytes([65, 1])) == []
    assert all(s.peek("led") == 1 for s in chain.servos)


def test_reg_write_then_broadcast_action(chain: EmulatedChain) -> None:
    for servo_id in (1, 3):
        (status,) = send(chain, servo_id, Instruction.REG_WRITE, bytes([65, 1]))
        assert status.error == 0
    assert chain.servo(1).peek("led") == 0 and chain.servo(1).peek("registered_instruction") == 1
    assert send(chain, BROADCAST_ID, Instruction.ACTION) == []
    assert [s.peek("led") for s in chain.servos] == [1, 0, 1]


def test_status_return_level_and_return_delay(chain: EmulatedChain) -> None:
    servo = chain.servo(3)
    servo.poke("status_return_level", 1)
    assert send(chain, 3, Instruction.WRITE, bytes([65, 1])) == []
    assert len(send(chain, 3, Instruction.READ, bytes([65, 1]))) == 1
    servo.poke("status_return_level", 0)
    assert send(chain, 3, Instruction.READ, bytes([65, 1])) == []
    assert len(send(chain, 3, Instruction.PING)) == 1
    servo.poke("return_delay_time", 100)  # 2 µs units
    (reply,) = chain.receive(build_instruction(3, Instruction.PING))
    assert reply.start_s == pytest.approx(200e-6 + servo.processing_time_s)


def test_sync_write_moves_the_goals_silently(chain: EmulatedChain) -> None:
    params = bytes([116, 4])
    for servo_id, goal in ((1, 1000), (2, 2000), (3, 3000)):
        params += bytes([servo_id]) + goal.to_bytes(4, "little")
    assert send(chain, BROADCAST_ID, Instruction.SYNC_WRITE, params) == []
    assert [s.peek("goal_position") for s in chain.servos] == [1000, 2000, 3000]


def test_bulk_read_answers_in_request_order_and_stops_at_a_silent_servo(
    chain: EmulatedChain,
) -> None:
    request = bytes([0, 4, 3, 132, 1, 2, 65, 4, 1, 132])
    packets = send(chain, BROADCAST_ID, Instruction.BULK_READ, request)
    assert [(p.servo_id, len(p.params)) for p in packets] == [(3, 4), (2, 1), (1, 4)]
    replies = chain.receive(build_instruction(BROADCAST_ID, Instruction.BULK_READ, request))
    assert [r.start_s for r in replies] == sorted(r.start_s for r in replies)
    chain.silence(2)
    packets = send(chain, BROADCAST_ID, Instruction.BULK_READ, request)
    assert [p.servo_id for p in packets] == [3]


def test_factory_reset_answers_then_resets_everything_but_the_protocol(
    chain: EmulatedChain,
) -> None:
    chain.servo(2).poke("return_delay_time", 0)
    chain.servo(2).poke("baud_rate", 3)  # 1 Mbps: the factory rate is 57600
    (status,) = send(chain, 2, Instruction.FACTORY_RESET)
    assert (status.servo_id, status.error) == (2, 0)
    (reset,) = [s for s in chain.servos if s.peek("return_delay_time") == 250 and s.baud == 57600]
    assert (reset.servo_id, reset.protocol) == (1, 1.0)


def test_mixed_chain_each_servo_answers_its_own_protocol() -> None:
    from snakebot.emulation import protocol

    p2 = VirtualServo("XL430-W250", 1, baud=BAUD)
    p1 = VirtualServo("XM430-W350", 2, baud=BAUD)
    p1.poke("protocol_type", 1)
    chain = EmulatedChain([p2, p1], baud=BAUD)
    assert len(send(chain, 2, Instruction.PING)) == 1 and send(chain, 1, Instruction.PING) == []
    ping2 = [protocol.build_instruction(i, protocol.Instruction.PING) for i in (1, 2)]
    assert [len(chain.receive(p)) for p in ping2] == [1, 0]
