"""EmulatedChain at the byte level: who answers, in what order, when, and with what faults."""

import itertools

import pytest

from snakebot.emulation import EmulatedChain, HardwareError, VirtualServo, make_chain_for_ids
from snakebot.emulation.errors import EmulationError
from snakebot.emulation.protocol import (
    ALERT_BIT,
    BROADCAST_ID,
    Instruction,
    Packet,
    StatusError,
    build_instruction,
    parse_packets,
)
from snakebot.emulation.wire import BusReply

BAUD = 1_000_000


def h(text: str) -> bytes:
    return bytes.fromhex(text)


def ask(chain: EmulatedChain, servo_id: int, inst: int, params: bytes = b"") -> list[Packet]:
    replies = chain.receive(build_instruction(servo_id, inst, params))
    return [p for r in replies for p in parse_packets(r.data)]


def read_params(address: int, length: int) -> bytes:
    return address.to_bytes(2, "little") + length.to_bytes(2, "little")


def write_params(address: int, value: int, size: int) -> bytes:
    return address.to_bytes(2, "little") + value.to_bytes(size, "little", signed=True)


@pytest.fixture
def chain() -> EmulatedChain:
    return make_chain_for_ids("XM430-W350", [1, 2, 3], BAUD)


def test_ping_read_write_round_trip(chain: EmulatedChain) -> None:
    assert ask(chain, 2, Instruction.PING) == [Packet(2, 0x55, h("00 FC 03 2E"))]
    assert ask(chain, 2, Instruction.WRITE, write_params(116, 3000, 4)) == [
        Packet(2, 0x55, h("00"))
    ]
    (reply,) = ask(chain, 2, Instruction.READ, read_params(116, 4))
    assert reply.error == 0 and int.from_bytes(reply.data, "little") == 3000
    assert ask(chain, 9, Instruction.PING) == []


def test_reply_waits_for_return_delay_and_processing(chain: EmulatedChain) -> None:
    (reply,) = chain.receive(build_instruction(1, Instruction.PING))
    servo = chain.servo(1)
    assert reply.start_s == pytest.approx(500e-6 + servo.processing_time_s)
    assert reply.end_s(BAUD) == pytest.approx(reply.start_s + 14 * 10e-6)


def test_broadcast_ping_answers_in_id_order_one_after_another() -> None:
    chain = make_chain_for_ids("XL430-W250", [3, 1, 2], BAUD)
    replies = chain.receive(build_instruction(BROADCAST_ID, Instruction.PING))
    assert [parse_packets(r.data)[0].servo_id for r in replies] == [1, 2, 3]
    for earlier, later in itertools.pairwise(replies):
        assert later.start_s >= earlier.end_s(BAUD) + 500e-6


def test_broadcast_read_and_write_never_answer(chain: EmulatedChain) -> None:
    assert ask(chain, BROADCAST_ID, Instruction.WRITE, write_params(65, 1, 1)) == []
    assert all(s.peek("led") == 1 for s in chain.servos)
    assert ask(chain, BROADCAST_ID, Instruction.READ, read_params(65, 1)) == []


@pytest.mark.parametrize(
    ("level", "ping", "read", "write"),
    [(0, True, False, False), (1, True, True, False), (2, True, True, True)],
)
def test_status_return_level(
    chain: EmulatedChain, level: int, ping: bool, read: bool, write: bool
) -> None:
    chain.servo(1).poke("status_return_level", level)
    assert bool(ask(chain, 1, Instruction.PING)) is ping
    assert bool(ask(chain, 1, Instruction.READ, read_params(132, 4))) is read
    assert bool(ask(chain, 1, Instruction.WRITE, write_params(65, 1, 1))) is write
    assert chain.servo(1).peek("led") == 1


def test_error_replies_carry_the_error_number(chain: EmulatedChain) -> None:
    (reply,) = ask(chain, 1, Instruction.WRITE, write_params(132, 1, 4))
    assert reply.error == StatusError.ACCESS
    (reply,) = ask(chain, 1, 0x7F)
    assert reply.error == StatusError.INSTRUCTION
    (reply,) = ask(chain, 1, Instruction.ACTION)
    assert reply.error == StatusError.INSTRUCTION


def test_sync_read_answers_in_parameter_order(chain: EmulatedChain) -> None:
    chain.servo(3).poke("goal_position", 1000)
    packets = ask(chain, BROADCAST_ID, Instruction.SYNC_READ, read_params(116, 4) + bytes([3, 1]))
    assert [(p.servo_id, int.from_bytes(p.data, "little")) for p in packets] == [
        (3, 1000),
        (1, 2048),
    ]


def test_fast_sync_read_is_one_packet_with_a_segment_per_servo(chain: EmulatedChain) -> None:
    chain.servo(2).poke("goal_position", 2079)
    chain.servo(1).poke("goal_position", 166)
    replies = chain.receive(
        build_instruction(
            BROADCAST_ID, Instruction.FAST_SYNC_READ, read_params(116, 4) + bytes([1, 2])
        )
    )
    wire = b"".join(r.data for r in replies)
    assert wire == h("FF FF FD 00 FE 11 00 55 00 01 A6 00 00 00 74 3B 00 02 1F 08 00 00 1C 36")


def test_bulk_read_and_fast_bulk_read(chain: EmulatedChain) -> None:
    params = h("01 90 00 02 00 02 92 00 01 00")
    packets = ask(chain, BROADCAST_ID, Instruction.BULK_READ, params)
    assert [(p.servo_id, p.data) for p in packets] == [(1, h("78 00")), (2, h("1E"))]
    replies = chain.receive(build_instruction(BROADCAST_ID, Instruction.FAST_BULK_READ, params))
    (fast,) = parse_packets(b"".join(r.data for r in replies))
    assert fast.servo_id == BROADCAST_ID and len(fast.params) == 9
    assert fast.params[:4] == h("00 01 78 00") and fast.params[6:] == h("00 02 1E")


def test_sync_write_and_bulk_write_change_every_listed_servo(chain: EmulatedChain) -> None:
    sync = h("74 00 04 00 01 96 00 00 00 02 AA 00 00 00")
    assert chain.receive(build_instruction(BROADCAST_ID, Instruction.SYNC_WRITE, sync)) == []
    assert [chain.servo(i).peek("goal_position") for i in (1, 2, 3)] == [150, 170, 2048]
    bulk = h("01 20 00 02 00 A0 00 02 1F 00 01 00 50")
    assert chain.receive(build_instruction(BROADCAST_ID, Instruction.BULK_WRITE, bulk)) == []
    assert chain.servo(1).peek("max_voltage_limit") == 160
    assert chain.servo(2).peek("temperature_limit") == 80


def test_reg_write_then_broadcast_action(chain: EmulatedChain) -> None:
    for servo_id in (1, 2):
        ask(chain, servo_id, Instruction.REG_WRITE, write_params(116, 1000 + servo_id, 4))
    assert chain.servo(1).peek("goal_position") == 2048
    assert chain.receive(build_instruction(BROADCAST_ID, Instruction.ACTION)) == []
    assert [chain.servo(i).peek("goal_position") for i in (1, 2, 3)] == [1001, 1002, 2048]


def test_reboot_replies_then_restarts(chain: EmulatedChain) -> None:
    chain.latch_hardware_error(1, HardwareError.OVERHEATING)
    (reply,) = ask(chain, 1, Instruction.REBOOT)
    assert reply.error == ALERT_BIT
    assert chain.servo(1).hardware_error == 0
    assert ask(chain, 1, Instruction.PING)[0].error == 0


def test_broadcast_factory_reset_all_is_ignored(chain: EmulatedChain) -> None:
    chain.servo(2).poke("return_delay_time", 0)
    chain.receive(build_instruction(BROADCAST_ID, Instruction.FACTORY_RESET, b"\xff"))
    assert chain.servo(2).peek("return_delay_time") == 0
    chain.receive(build_instruction(BROADCAST_ID, Instruction.FACTORY_RESET, b"\x02"))
    assert chain.servo(2).peek("return_delay_time") == 250


def test_wrong_baud_servo_is_silent(chain: EmulatedChain) -> None:
    chain.servo(2).poke("baud_rate", 1)
    assert ask(chain, 2, Instruction.PING) == []
    chain.baud = 57600
    assert ask(chain, 2, Instruction.PING)[0].servo_id == 2
    assert ask(chain, 1, Instruction.PING) == []


def test_id_change_takes_effect_for_the_next_packet(chain: EmulatedChain) -> None:
    (reply,) = ask(chain, 3, Instruction.WRITE, write_params(7, 9, 1))
    assert reply.servo_id == 3
    assert ask(chain, 9, Instruction.PING)[0].servo_id == 9
    assert ask(chain, 3, Instruction.PING) == []


def test_secondary_id_writes_without_replying(chain: EmulatedChain) -> None:
    for servo in chain.servos:
        servo.poke("secondary_shadow_id", 100)
    assert ask(chain, 100, Instruction.WRITE, write_params(65, 1, 1)) == []
    assert all(s.peek("led") == 1 for s in chain.servos)


def test_silenced_servo_neither_hears_nor_answers(chain: EmulatedChain) -> None:
    chain.silence(2)
    assert ask(chain, 2, Instruction.WRITE, write_params(65, 1, 1)) == []
    assert chain.servo(2).peek("led") == 0
    packets = ask(
        chain, BROADCAST_ID, Instruction.SYNC_READ, read_params(132, 4) + bytes([1, 2, 3])
    )
    assert [p.servo_id for p in packets] == [1, 3]
    chain.silence(2, False)
    assert ask(chain, 2, Instruction.PING)


def test_dropped_replies_still_run_the_instruction(chain: EmulatedChain) -> None:
    chain.drop_replies(1, next_n=1)
    assert ask(chain, 1, Instruction.WRITE, write_params(65, 1, 1)) == []
    assert chain.servo(1).peek("led") == 1
    assert ask(chain, 1, Instruction.PING)
    chain.drop_replies(1, probability=1.0)
    assert ask(chain, 1, Instruction.PING) == []
    chain.clear_faults()
    assert ask(chain, 1, Instruction.PING)


def test_corrupted_reply_fails_its_crc(chain: EmulatedChain) -> None:
    chain.corrupt_replies(3, next_n=1)
    (reply,) = chain.receive(build_instruction(3, Instruction.PING))
    assert reply.data[:7] == h("FF FF FD 00 03 07 00") and parse_packets(reply.data) == []
    assert ask(chain, 3, Instruction.PING)


def test_delayed_reply_moves_later(chain: EmulatedChain) -> None:
    chain.delay_replies(1, 0.05)
    (reply,) = chain.receive(build_instruction(1, Instruction.PING))
    assert reply.start_s > 0.05


def test_fault_targets_must_exist(chain: EmulatedChain) -> None:
    with pytest.raises(EmulationError, match="IDs on the bus"):
        chain.silence(42)


def test_duplicate_ids_both_obey_and_their_replies_collide() -> None:
    first = VirtualServo("XL430-W250", 1, baud=BAUD, processing_time_s=20e-6)
    second = VirtualServo("XL430-W250", 1, baud=BAUD, processing_time_s=27e-6)
    chain = EmulatedChain([first, second], baud=BAUD)
    replies = chain.receive(build_instruction(1, Instruction.WRITE, write_params(65, 1, 1)))
    assert first.peek("led") == second.peek("led") == 1
    assert len(replies) == 1 and parse_packets(replies[0].data) == []


def test_duplicate_ids_with_identical_timing_overlap_cleanly() -> None:
    servos = [VirtualServo("XL430-W250", 1, baud=BAUD, processing_time_s=20e-6) for _ in range(2)]
    chain = EmulatedChain(servos, baud=BAUD)
    assert ask(chain, 1, Instruction.PING) == [Packet(1, 0x55, h("00 24 04 2E"))]


def test_advance_moves_every_servo(chain: EmulatedChain) -> None:
    for servo in chain.servos:
        servo.poke("torque_enable", 1)
        servo.poke("goal_position", 2148)
    chain.advance(1.0)
    assert chain.now_s == 1.0
    assert [s.peek("present_position") for s in chain.servos] == [2148] * 3


def test_two_packets_in_one_chunk_are_answered_in_turn(chain: EmulatedChain) -> None:
    data = build_instruction(1, Instruction.PING) + build_instruction(2, Instruction.PING)
    replies: list[BusReply] = chain.receive(data)
    assert [parse_packets(r.data)[0].servo_id for r in replies] == [1, 2]
    assert replies[1].start_s >= replies[0].end_s(BAUD)


def test_bytes_left_waiting_by_a_starved_transport_are_fed_before_the_watchdog_judges() -> None:
    chain = make_chain_for_ids("XL430-W250", [1, 2], BAUD)
    for servo_id in (1, 2):
        ask(chain, servo_id, Instruction.WRITE, write_params(64, 1, 1))  # torque on
        ask(chain, servo_id, Instruction.WRITE, write_params(98, 5, 1))  # 100 ms watchdog
    chain.advance(0.5, bytes_waiting=True)  # a ping to ID 1 arrived somewhere in that 0.5 s
    ask(chain, 1, Instruction.PING)
    chain.advance(0.001)
    assert not chain.servo(1).watchdog_tripped
    assert chain.servo(2).watchdog_tripped  # nothing was sent to it: the time still counts
    chain.advance(0.5)
    assert chain.servo(1).watchdog_tripped


def test_a_partial_packet_survives_a_starved_gap_but_not_an_idle_line() -> None:
    chain = make_chain_for_ids("XL430-W250", [1], BAUD)
    ping = build_instruction(1, Instruction.PING)
    assert chain.receive(ping[:5]) == []
    chain.advance(0.5)
    assert len(chain.receive(ping[5:], idle_s=0.0)) == 1
    assert chain.receive(ping[:5]) == []
    assert chain.receive(ping[5:], idle_s=0.05) == []  # the receiver gave up on the first half
