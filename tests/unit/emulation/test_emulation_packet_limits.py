"""A status packet never outgrows the 1024-byte packet buffer (SDK RXPACKET_MAX_LEN).

A Fast Sync/Bulk Read puts every servo's part into one packet; a request whose packet would not
fit gets no reply at all, as ROBOTIS's reference slave (Dynamixel2Arduino `Slave`) answers nothing
when a reply would not fit its packet buffer. The chain must survive the request and keep serving.
"""

import pytest

from snakebot.emulation import make_chain_for_ids
from snakebot.emulation.protocol import (
    BROADCAST_ID,
    MAX_PACKET_BYTES,
    Instruction,
    build_instruction,
    parse_packets,
)

BAUD = 1_000_000


def sync_read(address: int, length: int, ids: list[int]) -> bytes:
    params = address.to_bytes(2, "little") + length.to_bytes(2, "little") + bytes(ids)
    return params


def test_the_84_byte_fast_sync_read_that_overflowed_the_length_field_gets_no_reply() -> None:
    chain = make_chain_for_ids("XL430-W250", range(1, 13), BAUD)
    packet = build_instruction(
        BROADCAST_ID, Instruction.FAST_SYNC_READ, sync_read(0, 1000, list(range(1, 71)))
    )
    assert len(packet) == 84
    assert chain.receive(packet) == []
    replies = chain.receive(build_instruction(7, Instruction.PING))
    assert [p.servo_id for r in replies for p in parse_packets(r.data)] == [7]


@pytest.mark.parametrize(
    ("length", "answered"), [(250, True), (251, False)], ids=["1024 bytes", "1028 bytes"]
)
def test_a_fast_sync_read_is_answered_only_while_its_packet_fits(
    length: int, answered: bool
) -> None:
    chain = make_chain_for_ids("XL430-W250", [1, 2, 3, 4], BAUD)
    packet = build_instruction(
        BROADCAST_ID, Instruction.FAST_SYNC_READ, sync_read(0, length, [1, 2, 3, 4])
    )
    wire = b"".join(r.data for r in chain.receive(packet))
    if answered:
        assert len(wire) == MAX_PACKET_BYTES
        (reply,) = parse_packets(wire)
        assert reply.servo_id == BROADCAST_ID and reply.is_status
    else:
        assert wire == b""


def test_a_fast_bulk_read_too_long_for_one_packet_gets_no_reply() -> None:
    chain = make_chain_for_ids("XL430-W250", [1, 2, 3], BAUD)
    params = b"".join(
        bytes([servo_id]) + (0).to_bytes(2, "little") + (400).to_bytes(2, "little")
        for servo_id in (1, 2, 3)
    )
    assert chain.receive(build_instruction(BROADCAST_ID, Instruction.FAST_BULK_READ, params)) == []
    # The same reads as a plain Bulk Read are three packets, each well inside the limit.
    plain = chain.receive(build_instruction(BROADCAST_ID, Instruction.BULK_READ, params))
    assert [len(r.data) for r in plain] == [411, 411, 411]
