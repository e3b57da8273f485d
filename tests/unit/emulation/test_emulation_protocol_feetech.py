"""The Feetech FT-SCS codec against the worked packets of Feetech's wiki (protocol/ft-scs.md)."""

import importlib
import sys

import pytest

from snakebot.emulation.protocol_feetech import (
    ErrorBit,
    Instruction,
    StreamParser,
    build_instruction,
    build_status,
    parse_packets,
)

# Feetech wiki docs/en/reference/protocol/ft-scs.md worked examples (servo-families.md §1.1).
INSTRUCTIONS = [
    ("FF FF 01 02 01 FB", 1, Instruction.PING, b""),
    ("FF FF 01 04 02 38 02 BE", 1, Instruction.READ, bytes([0x38, 0x02])),
    (
        "FF FF 01 09 03 2A 00 08 00 00 E8 03 D5",
        1,
        Instruction.WRITE,
        bytes.fromhex("2A 00 08 00 00 E8 03"),
    ),
    ("FF FF FE 06 82 38 08 01 02 36", 0xFE, Instruction.SYNC_READ, bytes.fromhex("38 08 01 02")),
    ("FF FF 01 02 0A F2", 1, Instruction.RESET, b""),
    ("FF FF 01 02 06 F6", 1, Instruction.RECOVERY, b""),
    ("FF FF 01 02 08 F4", 1, Instruction.RESTART, b""),
]
STATUSES = [
    ("FF FF 01 02 00 FC", 1, 0, b""),
    ("FF FF 01 04 00 18 05 DD", 1, 0, bytes([0x18, 0x05])),  # Present Position 1304, LE
]


@pytest.mark.parametrize(("wire", "servo_id", "instruction", "params"), INSTRUCTIONS)
def test_wiki_instruction_packets(
    wire: str, servo_id: int, instruction: int, params: bytes
) -> None:
    data = bytes.fromhex(wire)
    assert build_instruction(servo_id, instruction, params) == data
    (packet,) = parse_packets(data)
    assert (packet.servo_id, packet.instruction, packet.params) == (servo_id, instruction, params)


@pytest.mark.parametrize(("wire", "servo_id", "error", "params"), STATUSES)
def test_wiki_status_packets(wire: str, servo_id: int, error: int, params: bytes) -> None:
    assert build_status(servo_id, error, params) == bytes.fromhex(wire)


def test_status_bits_are_the_sdk_error_bits() -> None:
    # The package re-exports the handler class under its module's name: ask for the module.
    importlib.import_module("scservo_sdk")
    sdk = sys.modules["scservo_sdk.protocol_packet_handler"]

    assert ErrorBit.VOLTAGE == sdk.ERRBIT_VOLTAGE
    assert ErrorBit.ANGLE == sdk.ERRBIT_ANGLE
    assert ErrorBit.OVERHEAT == sdk.ERRBIT_OVERHEAT
    assert ErrorBit.OVERCURRENT == sdk.ERRBIT_OVERELE
    assert ErrorBit.OVERLOAD == sdk.ERRBIT_OVERLOAD
    # Bit 7 would make the SDK drop the packet as a bad header.
    assert build_status(1, 0xFF)[4] == 0x7F


def test_a_bad_checksum_is_reported_not_served() -> None:
    damaged = bytearray.fromhex("FF FF 01 04 02 38 02 BE")
    damaged[-1] ^= 0x01
    parser = StreamParser(stale_after_s=None)
    (packet,) = parser.feed(bytes(damaged))
    assert not packet.intact
    assert parser.stats.crc_errors == 1
