"""The Protocol 1.0 codec against the e-Manual's worked packets, and its stream parser."""

import pytest
from hypothesis import given
from hypothesis import strategies as st

from snakebot.emulation.protocol1 import (
    ErrorBit,
    Instruction,
    StreamParser,
    build_instruction,
    build_status,
    checksum,
    parse_packets,
)

# e-Manual docs/en/dxl/protocol1.md examples (instruction and status packets).
GOLDEN = [
    ("FF FF 01 02 01 FB", 1, Instruction.PING, b""),
    ("FF FF 01 04 02 2B 01 CC", 1, Instruction.READ, bytes([0x2B, 0x01])),
    ("FF FF FE 04 03 03 01 F6", 0xFE, Instruction.WRITE, bytes([0x03, 0x01])),
    (
        "FF FF FE 18 83 1E 04 00 10 00 50 01 01 20 02 60 03 02 30 00 70 01 03 20 02 80 03 12",
        0xFE,
        Instruction.SYNC_WRITE,
        bytes.fromhex("1E 04 00 10 00 50 01 01 20 02 60 03 02 30 00 70 01 03 20 02 80 03"),
    ),
    (
        "FF FF FE 09 92 00 02 01 1E 02 02 24 1D",
        0xFE,
        Instruction.BULK_READ,
        bytes.fromhex("00 02 01 1E 02 02 24"),
    ),
]


@pytest.mark.parametrize(("wire", "servo_id", "instruction", "params"), GOLDEN)
def test_golden_instruction_packets(
    wire: str, servo_id: int, instruction: int, params: bytes
) -> None:
    data = bytes.fromhex(wire)
    assert build_instruction(servo_id, instruction, params) == data
    (packet,) = parse_packets(data)
    assert (packet.servo_id, packet.instruction, packet.params) == (servo_id, instruction, params)


def test_golden_status_packets() -> None:
    assert build_status(1, 0) == bytes.fromhex("FF FF 01 02 00 FC")
    assert build_status(1, 0, bytes([0x20])) == bytes.fromhex("FF FF 01 03 00 20 DB")
    overload_and_overheat = ErrorBit.OVERLOAD | ErrorBit.OVERHEATING
    assert build_status(1, overload_and_overheat) == bytes.fromhex("FF FF 01 02 24 D8")
    assert checksum(bytes.fromhex("01 02 24")) == 0xD8


def test_parser_resyncs_after_garbage_and_split_chunks() -> None:
    ping = build_instruction(3, Instruction.PING)
    stream = b"\x00\xff\x12\xff\xff\xff" + ping + b"\xff\xff\xff\x07" + ping
    parser = StreamParser(stale_after_s=None)
    found = [
        p
        for chunk in (stream[i : i + 3] for i in range(0, len(stream), 3))
        for p in parser.feed(chunk)
        if p.intact
    ]
    assert [(p.servo_id, p.instruction) for p in found] == [(3, Instruction.PING)] * 2


def test_bad_checksum_is_reported_once_and_costs_one_byte() -> None:
    ping = bytearray(build_instruction(5, Instruction.PING))
    ping[-1] ^= 0x01
    read = build_instruction(5, Instruction.READ, bytes([36, 2]))
    parser = StreamParser(stale_after_s=None)
    packets = parser.feed(bytes(ping) + read)
    assert [(p.servo_id, p.intact) for p in packets] == [(5, False), (5, True)]
    assert parser.stats.crc_errors == 1 and parser.stats.packets == 1


def test_protocol2_packets_are_not_protocol1_packets() -> None:
    from snakebot.emulation import protocol

    data = protocol.build_instruction(1, protocol.Instruction.PING)
    data += protocol.build_instruction(0xFE, protocol.Instruction.SYNC_READ, bytes(6))
    assert parse_packets(data) == []
    assert protocol.parse_packets(build_instruction(0xFD, Instruction.PING)) == []


def test_a_partial_packet_goes_stale() -> None:
    ping = build_instruction(1, Instruction.PING)
    parser = StreamParser(stale_after_s=0.01)
    assert parser.feed(ping[:3], 0.0) == []
    assert [p.intact for p in parser.feed(ping, 0.5)] == [True]
    assert parser.stats.stale_resets == 1


@given(st.binary(max_size=400), st.integers(1, 16))
def test_parser_never_raises_and_finds_what_it_was_given(noise: bytes, chunk: int) -> None:
    packet = build_instruction(7, Instruction.WRITE, bytes([30, 0x00, 0x02]))
    stream = noise + b"\x00" * 250 + packet  # 250 zeros: no header can straddle into the packet
    parser = StreamParser(stale_after_s=None)
    found = []
    for i in range(0, len(stream), chunk):
        found += [p for p in parser.feed(stream[i : i + chunk]) if p.intact]
    assert found[-1].params == bytes([30, 0x00, 0x02])
