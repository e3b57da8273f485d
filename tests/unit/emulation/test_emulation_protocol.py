"""The Protocol 2.0 codec against the e-Manual / reference §1.9 vectors, byte for byte."""

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from snakebot.emulation.protocol import (
    CRC_TABLE,
    Instruction,
    Packet,
    StreamParser,
    build_fast_status,
    build_instruction,
    build_status,
    crc16,
    fast_status_segments,
    parse_packets,
    stuff,
    unstuff,
)


def h(text: str) -> bytes:
    return bytes.fromhex(text)


MODEL_1030_FW38 = h("06 04 26")

INSTRUCTION_VECTORS = [
    ("ping ID1", 1, Instruction.PING, "", "FF FF FD 00 01 03 00 01 19 4E"),
    ("broadcast ping", 0xFE, Instruction.PING, "", "FF FF FD 00 FE 03 00 01 31 42"),
    ("read 132/4", 1, Instruction.READ, "84 00 04 00", "FF FF FD 00 01 07 00 02 84 00 04 00 1D 15"),
    (
        "write goal 512",
        1,
        Instruction.WRITE,
        "74 00 00 02 00 00",
        "FF FF FD 00 01 09 00 03 74 00 00 02 00 00 CA 89",
    ),
    (
        "reg write velocity 200",
        1,
        Instruction.REG_WRITE,
        "68 00 C8 00 00 00",
        "FF FF FD 00 01 09 00 04 68 00 C8 00 00 00 AE 8E",
    ),
    ("action", 1, Instruction.ACTION, "", "FF FF FD 00 01 03 00 05 02 CE"),
    ("reboot", 1, Instruction.REBOOT, "", "FF FF FD 00 01 03 00 08 2F 4E"),
    (
        "clear multi-turn",
        1,
        Instruction.CLEAR,
        "01 44 58 4C 22",
        "FF FF FD 00 01 08 00 10 01 44 58 4C 22 B1 DC",
    ),
    (
        "factory reset keep ID",
        1,
        Instruction.FACTORY_RESET,
        "01",
        "FF FF FD 00 01 04 00 06 01 A1 E6",
    ),
    (
        "sync read",
        0xFE,
        Instruction.SYNC_READ,
        "84 00 04 00 01 02",
        "FF FF FD 00 FE 09 00 82 84 00 04 00 01 02 CE FA",
    ),
    (
        "sync write",
        0xFE,
        Instruction.SYNC_WRITE,
        "74 00 04 00 01 96 00 00 00 02 AA 00 00 00",
        "FF FF FD 00 FE 11 00 83 74 00 04 00 01 96 00 00 00 02 AA 00 00 00 82 87",
    ),
    (
        "bulk read",
        0xFE,
        Instruction.BULK_READ,
        "01 90 00 02 00 02 92 00 01 00",
        "FF FF FD 00 FE 0D 00 92 01 90 00 02 00 02 92 00 01 00 1A 05",
    ),
    (
        "bulk write",
        0xFE,
        Instruction.BULK_WRITE,
        "01 20 00 02 00 A0 00 02 1F 00 01 00 50",
        "FF FF FD 00 FE 10 00 93 01 20 00 02 00 A0 00 02 1F 00 01 00 50 B7 68",
    ),
    (
        "stuffed write",
        1,
        Instruction.WRITE,
        "74 00 FF FF FD 00",
        "FF FF FD 00 01 0A 00 03 74 00 FF FF FD FD 00 21 E7",
    ),
    (
        "fast sync read",
        0xFE,
        Instruction.FAST_SYNC_READ,
        "84 00 04 00 01 02",
        "FF FF FD 00 FE 09 00 8A 84 00 04 00 01 02 4D 72",
    ),
]

STATUS_VECTORS = [
    ("ping ID1", 1, 0, MODEL_1030_FW38, "FF FF FD 00 01 07 00 55 00 06 04 26 65 5D"),
    ("ping ID2", 2, 0, MODEL_1030_FW38, "FF FF FD 00 02 07 00 55 00 06 04 26 6F 6D"),
    ("read 166", 1, 0, h("A6 00 00 00"), "FF FF FD 00 01 08 00 55 00 A6 00 00 00 8C C0"),
    ("read 2079", 2, 0, h("1F 08 00 00"), "FF FF FD 00 02 08 00 55 00 1F 08 00 00 BA BE"),
    ("write ok", 1, 0, b"", "FF FF FD 00 01 04 00 55 00 A1 0C"),
    ("bulk voltage 119", 1, 0, h("77 00"), "FF FF FD 00 01 06 00 55 00 77 00 C3 69"),
    ("bulk temperature 36", 2, 0, h("24"), "FF FF FD 00 02 05 00 55 00 24 8B A9"),
]

FAST_REPLY = "FF FF FD 00 FE 11 00 55 00 01 A6 00 00 00 74 3B 00 02 1F 08 00 00 1C 36"


@pytest.mark.parametrize(("case", "servo_id", "inst", "params", "wire"), INSTRUCTION_VECTORS)
def test_instruction_vectors(case: str, servo_id: int, inst: int, params: str, wire: str) -> None:
    assert build_instruction(servo_id, inst, h(params)) == h(wire), case
    assert parse_packets(h(wire)) == [Packet(servo_id, inst, h(params))], case


@pytest.mark.parametrize(("case", "servo_id", "error", "data", "wire"), STATUS_VECTORS)
def test_status_vectors(case: str, servo_id: int, error: int, data: bytes, wire: str) -> None:
    assert build_status(servo_id, error, data) == h(wire), case
    (packet,) = parse_packets(h(wire))
    assert packet.is_status and packet.servo_id == servo_id
    assert (packet.error, packet.data) == (error, data)


def test_fast_sync_read_reply_vector_and_cumulative_crcs() -> None:
    entries = [(1, 0, h("A6 00 00 00")), (2, 0, h("1F 08 00 00"))]
    wire = build_fast_status(entries)
    assert wire == h(FAST_REPLY)
    first, second = fast_status_segments(entries)
    assert first == wire[:16] and second == wire[16:]
    assert crc16(wire[:14]) == int.from_bytes(wire[14:16], "little")
    (packet,) = parse_packets(wire)
    assert packet.servo_id == 0xFE and packet.is_status
    assert packet.params == wire[8:-2]


def test_fast_reply_is_never_stuffed() -> None:
    entries = [(1, 0, h("FF FF FD 00"))]
    wire = build_fast_status(entries)
    assert wire[10:14] == h("FF FF FD 00") and len(wire) == 8 + 1 * (4 + 4)
    assert parse_packets(wire)[0].params[2:6] == h("FF FF FD 00")


def test_crc_table_and_check_value() -> None:
    assert CRC_TABLE[:5] == (0x0000, 0x8005, 0x800F, 0x000A, 0x801B)
    assert CRC_TABLE[-2:] == (0x8207, 0x0202)
    assert crc16(b"123456789") == 0xFEE8
    assert crc16(h("FF FF FD 00 01 03 00 01")) == 0x4E19
    assert crc16(b"56789", crc16(b"1234")) == 0xFEE8


def test_stuffing_examples() -> None:
    assert stuff(h("03 74 00 FF FF FD 00")) == h("03 74 00 FF FF FD FD 00")
    assert stuff(h("FF FF FF FD")) == h("FF FF FF FD FD")
    assert stuff(h("FF FD FF FF")) == h("FF FD FF FF")
    assert unstuff(h("FF FF FD FD FF FF FD FD")) == h("FF FF FD FF FF FD")


@given(st.lists(st.sampled_from([0xFF, 0xFD, 0x00, 0x55]), max_size=64).map(bytes))
def test_stuffing_round_trip_and_no_header_left(body: bytes) -> None:
    stuffed = stuff(body)
    assert unstuff(stuffed) == body
    for index in range(len(stuffed) - 2):
        if stuffed[index : index + 3] == b"\xff\xff\xfd":
            assert stuffed[index + 3 : index + 4] == b"\xfd"


@given(
    servo_id=st.integers(0, 0xFC),
    instruction=st.sampled_from(list(Instruction)),
    params=st.binary(max_size=40),
)
def test_build_parse_round_trip(servo_id: int, instruction: int, params: bytes) -> None:
    wire = build_instruction(servo_id, instruction, params)
    assert parse_packets(wire) == [Packet(servo_id, instruction, params)]
    assert b"\xff\xff\xfd\x00" not in wire[4:]


@settings(max_examples=200)
@given(
    packets=st.lists(
        st.tuples(st.integers(0, 0xFC), st.binary(max_size=20)), min_size=1, max_size=4
    ),
    garbage=st.lists(st.binary(max_size=12), min_size=5, max_size=5),
    cuts=st.lists(st.integers(1, 200), max_size=6),
)
def test_parser_finds_packets_in_any_chunking_between_garbage(
    packets: list[tuple[int, bytes]], garbage: list[bytes], cuts: list[int]
) -> None:
    garbage = [g.replace(b"\xff", b"\x00") for g in garbage]
    stream = garbage[0]
    for index, (servo_id, params) in enumerate(packets):
        stream += build_instruction(servo_id, Instruction.WRITE, params) + garbage[index + 1]
    parser, found = StreamParser(stale_after_s=None), []
    start = 0
    for cut in sorted(set(cuts)):
        found += parser.feed(stream[start:cut])
        start = max(start, cut)
    found += parser.feed(stream[start:])
    assert found == [Packet(i, Instruction.WRITE, p) for i, p in packets]


def test_parser_drops_bad_crc_and_resyncs_on_the_next_packet() -> None:
    good = build_instruction(1, Instruction.PING)
    bad = bytearray(build_instruction(2, Instruction.PING))
    bad[-1] ^= 0x01
    parser = StreamParser(stale_after_s=None)
    assert parser.feed(bytes(bad) + good) == [Packet(1, Instruction.PING, b"")]
    assert parser.stats.crc_errors == 1 and parser.stats.packets == 1


def test_parser_rejects_bad_ids_reserved_bytes_and_lengths_without_raising() -> None:
    good = build_instruction(3, Instruction.PING)
    for header in (
        "FF FF FD 00 FD 03 00",
        "FF FF FD 00 FF 03 00",
        "FF FF FD 01 01 03 00",
        "FF FF FD 00 01 02 00",
        "FF FF FD 00 01 FF FF",
    ):
        parser = StreamParser(stale_after_s=None)
        assert parser.feed(h(header) + good) == [Packet(3, Instruction.PING, b"")], header
        assert parser.stats.bad_headers >= 1


def test_truncated_packet_is_forgotten_after_a_silence() -> None:
    parser = StreamParser(stale_after_s=0.02)
    truncated = build_instruction(1, Instruction.WRITE, bytes(50))[:20]
    assert parser.feed(truncated, now_s=0.0) == []
    good = build_instruction(1, Instruction.PING)
    assert parser.feed(good, now_s=0.001) == []  # still waiting for the long packet
    assert parser.feed(good, now_s=0.5) == [Packet(1, Instruction.PING, b"")]
    assert parser.stats.stale_resets == 1
