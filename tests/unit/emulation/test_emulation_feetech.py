"""The emulator's Feetech servos, byte for byte: the wiki's worked exchanges, the instruction set,
the EEPROM lock, the offset rule, sign-magnitude registers and each model's byte order."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest

from snakebot.emulation import EmulatedChain, ExternalMotion, VirtualServo, make_chain_for_ids
from snakebot.emulation.protocol_feetech import (
    BROADCAST_ID,
    ErrorBit,
    Instruction,
    build_instruction,
    parse_packets,
)
from snakebot.emulation.state_file import load_state, restore, save_state

BAUD = 1_000_000


def sts(ids: tuple[int, ...] = (1,)) -> EmulatedChain:
    return make_chain_for_ids("STS3215", ids, BAUD)


def send(chain: EmulatedChain, servo_id: int, instruction: int, params: bytes = b"") -> bytes:
    """What the wire carries back for one instruction packet."""
    replies = chain.receive(build_instruction(servo_id, instruction, params))
    return b"".join(r.data for r in replies)


def write(chain: EmulatedChain, servo_id: int, address: int, data: bytes) -> bytes:
    return send(chain, servo_id, Instruction.WRITE, bytes([address]) + data)


def read(chain: EmulatedChain, servo_id: int, address: int, length: int) -> bytes:
    (status,) = parse_packets(send(chain, servo_id, Instruction.READ, bytes([address, length])))
    assert status.servo_id == servo_id
    return status.params


def test_wiki_ping_exchange() -> None:
    assert sts().receive(bytes.fromhex("FF FF 01 02 01 FB"))[0].data == bytes.fromhex(
        "FF FF 01 02 00 FC"
    )


def test_wiki_read_exchange_position_1304() -> None:
    chain = sts()
    servo = chain.servo(1)
    servo.state = replace(servo.state, position_rad=(1304 - 2048) * 2 * math.pi / 4096)
    (reply,) = chain.receive(bytes.fromhex("FF FF 01 04 02 38 02 BE"))
    assert reply.data == bytes.fromhex("FF FF 01 04 00 18 05 DD")


def test_wiki_write_exchange_sets_goal_time_and_speed() -> None:
    chain = sts()
    (reply,) = chain.receive(bytes.fromhex("FF FF 01 09 03 2A 00 08 00 00 E8 03 D5"))
    assert reply.data == bytes.fromhex("FF FF 01 02 00 FC")
    servo = chain.servo(1)
    assert (servo.peek("goal_position"), servo.peek("goal_time"), servo.peek("goal_speed")) == (
        2048,
        0,
        1000,
    )


def test_wiki_sync_read_exchange_two_servos_eight_bytes_each() -> None:
    statuses = parse_packets(
        b"".join(
            r.data for r in sts((1, 2)).receive(bytes.fromhex("FF FF FE 06 82 38 08 01 02 36"))
        )
    )
    assert [(s.servo_id, len(s.params)) for s in statuses] == [(1, 8), (2, 8)]
    assert statuses[0].params[:2] == (2048).to_bytes(2, "little")


@pytest.mark.parametrize(
    ("wire", "answer"),
    [
        ("FF FF 01 02 0A F2", "FF FF 01 02 00 FC"),  # reset (the turn count)
        ("FF FF 01 02 06 F6", "FF FF 01 02 00 FC"),  # parameter recovery
        ("FF FF 01 02 08 F4", ""),  # restart: no status packet
    ],
)
def test_wiki_reset_recovery_and_restart_exchanges(wire: str, answer: str) -> None:
    replies = sts().receive(bytes.fromhex(wire))
    assert b"".join(r.data for r in replies) == bytes.fromhex(answer)


def test_sync_read_answers_in_the_order_of_the_request() -> None:
    chain = sts((1, 2, 3))
    request = bytes([0x38, 2, 3, 1, 2])
    statuses = parse_packets(send(chain, BROADCAST_ID, Instruction.SYNC_READ, request))
    assert [s.servo_id for s in statuses] == [3, 1, 2]
    assert all(s.params == (2048).to_bytes(2, "little") for s in statuses)


def test_sync_read_skips_an_absent_id_and_the_others_still_answer() -> None:
    chain = sts((1, 3))
    statuses = parse_packets(
        send(chain, BROADCAST_ID, Instruction.SYNC_READ, bytes([56, 2, 1, 2, 3]))
    )
    assert [s.servo_id for s in statuses] == [1, 3]


def test_sync_write_moves_each_servo_to_its_own_goal() -> None:
    chain = sts((1, 2))
    params = bytes([40, 1, 1, 1, 2, 1])  # torque on, both
    assert send(chain, BROADCAST_ID, Instruction.SYNC_WRITE, params) == b""
    goals = (
        bytes([42, 2, 1]) + (1000).to_bytes(2, "little") + bytes([2]) + (3000).to_bytes(2, "little")
    )
    assert send(chain, BROADCAST_ID, Instruction.SYNC_WRITE, goals) == b""
    chain.advance(3.0)
    assert abs(chain.servo(1).peek("present_position") - 1000) <= 1
    assert abs(chain.servo(2).peek("present_position") - 3000) <= 1


def test_restart_gives_no_reply_and_forgets_eeprom_written_while_locked() -> None:
    chain = sts()
    assert read(chain, 1, 55, 1) == b"\x01"  # Lock 1 from the factory
    write(chain, 1, 13, bytes([60]))  # Max Temperature Limit: takes effect at once
    assert read(chain, 1, 13, 1) == bytes([60])
    assert send(chain, 1, Instruction.RESTART) == b""
    assert read(chain, 1, 13, 1) == bytes([70])


def test_eeprom_written_with_lock_0_survives_a_restart_and_the_state_file(tmp_path: Path) -> None:
    chain = sts()
    write(chain, 1, 55, b"\x00")
    write(chain, 1, 5, bytes([7]))  # ID 7, saved
    write(chain, 7, 55, b"\x01")
    write(chain, 7, 13, bytes([60]))  # not saved
    send(chain, 7, Instruction.RESTART)
    assert read(chain, 7, 5, 1) == bytes([7])
    assert read(chain, 7, 13, 1) == bytes([70])
    write(chain, 7, 55, b"\x00")
    write(chain, 7, 13, bytes([65]))
    state = tmp_path / "state.json"
    save_state(state, chain.servos)
    fresh = VirtualServo("STS3215")
    fresh.serial_number = chain.servo(7).serial_number
    restore(fresh, load_state(state)[fresh.serial_number])
    assert (fresh.servo_id, fresh.peek("temperature_limit"), fresh.peek("lock")) == (7, 65, 1)


def test_recovery_restores_all_but_the_id() -> None:
    chain = sts()
    write(chain, 1, 55, b"\x00")
    write(chain, 1, 5, bytes([9]))
    write(chain, 9, 6, bytes([4]))  # 115200
    chain.baud = 115_200
    write(chain, 9, 13, bytes([50]))
    assert parse_packets(send(chain, 9, Instruction.RECOVERY))[0].servo_id == 9
    chain.baud = BAUD
    assert read(chain, 9, 13, 1) == bytes([70])
    assert read(chain, 9, 6, 1) == bytes([0])


def test_offset_rule_present_is_actual_minus_offset() -> None:
    chain = sts()
    servo = chain.servo(1)
    write(chain, 1, 31, (100 | 1 << 11).to_bytes(2, "little"))  # -100, sign bit 11
    assert servo.peek("homing_offset") == -100
    assert servo.peek("present_position") == 2048 + 100
    write(chain, 1, 31, (300).to_bytes(2, "little"))
    assert int.from_bytes(read(chain, 1, 56, 2), "little") == 2048 - 300


def test_a_negative_present_position_reads_sign_magnitude_bit_15() -> None:
    chain = sts()
    servo = chain.servo(1)
    write(chain, 1, 31, (2047).to_bytes(2, "little"))
    servo.state = replace(servo.state, position_rad=-math.pi / 2)  # actual 1024
    raw = int.from_bytes(read(chain, 1, 56, 2), "little")
    assert raw == (1 << 15) | (2047 - 1024)


def test_torque_128_makes_the_present_position_2048() -> None:
    chain = sts()
    servo = chain.servo(1)
    servo.state = replace(servo.state, position_rad=0.5)
    write(chain, 1, 40, bytes([128]))
    assert servo.peek("present_position") == 2048
    assert servo.peek("torque_enable") == 0
    send(chain, 1, Instruction.RESTART)
    assert servo.peek("present_position") == 2048  # the calibration is saved


def test_ofscal_sets_the_position_it_is_given() -> None:
    chain = sts()
    send(chain, 1, Instruction.OFSCAL, (1000).to_bytes(2, "little"))
    assert chain.servo(1).peek("present_position") == 1000


def test_response_level_0_answers_reads_and_pings_only() -> None:
    chain = sts()
    write(chain, 1, 8, b"\x00")
    assert write(chain, 1, 40, b"\x01") == b""
    assert chain.servo(1).peek("torque_enable") == 1
    assert read(chain, 1, 40, 1) == b"\x01"
    assert send(chain, 1, Instruction.PING) != b""


def test_silence_for_a_bad_checksum_and_an_unknown_instruction() -> None:
    chain = sts()
    damaged = bytearray(build_instruction(1, Instruction.PING))
    damaged[-1] ^= 0xFF
    assert chain.receive(bytes(damaged)) == []
    assert send(chain, 1, 0x92, bytes([0, 2, 1, 56])) == b""  # Dynamixel's Bulk Read


def test_a_broadcast_ping_of_two_servos_collides() -> None:
    (reply,) = sts((1, 2)).receive(build_instruction(BROADCAST_ID, Instruction.PING))
    assert reply.data not in (
        bytes.fromhex("FF FF 01 02 00 FC"),
        bytes.fromhex("FF FF 02 02 00 FB"),
    )


def test_reg_write_waits_for_action() -> None:
    chain = sts((1, 2))
    for servo_id in (1, 2):
        send(chain, servo_id, Instruction.REG_WRITE, bytes([40, 1]))
    assert read(chain, 1, 64, 1) == b"\x01"  # async write flag
    assert chain.servo(1).peek("torque_enable") == 0
    assert send(chain, BROADCAST_ID, Instruction.ACTION) == b""
    assert [chain.servo(i).peek("torque_enable") for i in (1, 2)] == [1, 1]


def test_status_byte_reports_overheating() -> None:
    chain = sts()
    servo = chain.servo(1)
    servo.state = replace(servo.state, temperature_c=80.0)
    chain.advance(0.02)
    (status,) = parse_packets(send(chain, 1, Instruction.PING))
    assert status.error & ErrorBit.OVERHEAT


def test_scs_words_are_big_endian() -> None:
    chain = make_chain_for_ids("SCS0009", (1,), BAUD)
    assert read(chain, 1, 3, 2) == (1284).to_bytes(2, "big")
    assert read(chain, 1, 9, 4) == (20).to_bytes(2, "big") + (1003).to_bytes(2, "big")
    assert read(chain, 1, 56, 2) == (512).to_bytes(2, "big")
    write(chain, 1, 40, b"\x01")
    write(chain, 1, 42, (700).to_bytes(2, "big"))
    chain.advance(2.0)
    assert read(chain, 1, 56, 2) == (700).to_bytes(2, "big")


def test_scs_lock_is_at_48() -> None:
    chain = make_chain_for_ids("SCS0009", (1,), BAUD)
    write(chain, 1, 48, b"\x00")
    write(chain, 1, 13, bytes([60]))
    send(chain, 1, Instruction.RESTART)
    assert read(chain, 1, 13, 1) == bytes([60])


def test_feetech_and_dynamixel_p1_servos_share_one_wire() -> None:
    chain = sts((1,))
    chain.add(VirtualServo("AX-12A", 2, baud=BAUD))
    assert parse_packets(send(chain, 1, Instruction.PING))[0].params == b""
    # An AX-12A's ping status has no parameters either; its model number reads at 0.
    assert read(chain, 2, 0, 2) == (12).to_bytes(2, "little")
    assert read(chain, 1, 3, 2) == (777).to_bytes(2, "little")


def test_an_overload_held_past_protection_time_drops_to_holding_torque() -> None:
    servo = VirtualServo("STS3215", 1, baud=BAUD, motion=ExternalMotion())
    chain = EmulatedChain([servo], baud=BAUD)
    write(chain, 1, 40, b"\x01")
    servo.state = replace(servo.state, effort=0.85)  # above Overload Torque 80 %
    chain.advance(1.9)  # Protection Time 200 x 10 ms = 2 s
    (status,) = parse_packets(send(chain, 1, Instruction.PING))
    assert status.error == 0
    chain.advance(0.2)
    (status,) = parse_packets(send(chain, 1, Instruction.PING))
    assert status.error & ErrorBit.OVERLOAD
    assert read(chain, 1, 65, 1) == bytes([ErrorBit.OVERLOAD])  # Servo status
    assert servo.peek("torque_limit") == 200  # Holding Torque 20 % of Max Torque 1000
    assert servo.peek("torque_enable") == 1


def test_scramble_leaves_one_feetech_servo_answering_reads_only() -> None:
    from snakebot.emulation.bench import scramble

    chain = sts((1, 2))
    scramble(chain, 0)
    servo = chain.servo(2)
    assert servo.peek("status_return_level") == 0
    assert write(chain, 2, 41, b"\x00") == b""
    assert read(chain, 2, 41, 1) == b"\x00"


def test_a_poked_eeprom_item_survives_a_restart() -> None:
    chain = sts()
    chain.servo(1).poke("homing_offset", 123)  # as a scrambled bench servo's settings
    send(chain, 1, Instruction.RESTART)
    assert chain.servo(1).peek("homing_offset") == 123


def test_an_scs_in_motor_mode_turns_by_goal_time_with_bit_10_the_direction() -> None:
    chain = make_chain_for_ids("SCS0009", (1,), BAUD)
    servo = chain.servo(1)
    write(chain, 1, 9, bytes(4))  # both angle limits 0: motor mode
    write(chain, 1, 40, b"\x01")
    write(chain, 1, 44, (500 | 1 << 10).to_bytes(2, "big"))  # 50 % duty, reverse
    chain.advance(0.2)
    assert servo.state.velocity_rad_s < 0
    write(chain, 1, 44, (500).to_bytes(2, "big"))
    chain.advance(0.2)
    assert servo.state.velocity_rad_s > 0
