"""What the host's UART receives when servo replies overlap on the half-duplex wire."""

from snakebot.emulation.protocol import build_status, parse_packets
from snakebot.emulation.wire import BusReply, byte_time_s, collide, merge_collisions

BAUD = 1_000_000
PING = build_status(1, 0, bytes([0x24, 0x04, 46]))
OTHER = build_status(1, 0, bytes([0x20, 0x04, 46]))


def test_byte_time_is_ten_bits() -> None:
    assert byte_time_s(1_000_000) == 10e-6
    assert BusReply(0.001, PING).end_s(BAUD) == 0.001 + 14 * 10e-6


def test_a_lone_reply_decodes_unchanged() -> None:
    assert collide([BusReply(0.0, PING)], BAUD).data == PING


def test_identical_replies_within_half_a_bit_overlap_cleanly() -> None:
    assert collide([BusReply(0.0, PING), BusReply(0.3e-6, PING)], BAUD).data == PING


def test_skewed_or_different_replies_garble() -> None:
    skewed = collide([BusReply(0.0, PING), BusReply(3e-6, PING)], BAUD)
    assert skewed.start_s == 0.0 and skewed.data != PING and parse_packets(skewed.data) == []
    mixed = collide([BusReply(0.0, PING), BusReply(0.0, OTHER)], BAUD)
    assert mixed.data == bytes(a & b for a, b in zip(PING, OTHER, strict=True))
    assert parse_packets(mixed.data) == []


def test_merge_only_touches_overlapping_replies() -> None:
    late = BusReply(0.01, OTHER)
    replies = merge_collisions([late, BusReply(0.0, PING), BusReply(50e-6, PING)], BAUD)
    assert len(replies) == 2 and replies[1] == late
    assert replies[0].start_s == 0.0 and replies[0].data != PING
    apart = [BusReply(0.0, PING), BusReply(200e-6, OTHER)]
    assert merge_collisions(apart, BAUD) == apart
