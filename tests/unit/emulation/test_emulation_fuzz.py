"""Random and malformed byte streams: the chain never raises and never answers garbage."""

from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from snakebot.emulation import EmulatedChain, make_chain_for_ids
from snakebot.emulation.protocol import (
    BROADCAST_ID,
    Instruction,
    build_instruction,
    parse_packets,
)

IDS = [1, 2, 3]
FUZZ = settings(
    max_examples=600, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow]
)


def fresh_chain() -> EmulatedChain:
    return make_chain_for_ids("XL430-W250", IDS, 1_000_000)


def feed(chain: EmulatedChain, data: bytes, cuts: list[int]) -> list[bytes]:
    out, start = [], 0
    for cut in [*sorted(set(cuts)), len(data)]:
        out += [r.data for r in chain.receive(data[start:cut])]
        start = max(start, cut)
    return out


header_pieces = st.sampled_from(
    [b"\xff\xff\xfd\x00", b"\xff\xff\xfd", b"\xff", b"\xfd\xfd", b"\x00"]
)
biased_bytes = st.lists(st.one_of(header_pieces, st.binary(max_size=16)), max_size=24).map(b"".join)


@FUZZ
@given(data=biased_bytes, cuts=st.lists(st.integers(0, 200), max_size=5))
def test_garbage_gets_no_reply(data: bytes, cuts: list[int]) -> None:
    assume(not parse_packets(data))
    assert feed(fresh_chain(), data, cuts) == []


@st.composite
def damaged_packets(draw: st.DrawFn) -> bytes:
    servo_id = draw(st.sampled_from([*IDS, BROADCAST_ID]))
    instruction = draw(st.sampled_from(list(Instruction)))
    packet = bytearray(build_instruction(servo_id, instruction, draw(st.binary(max_size=30))))
    damage = draw(st.sampled_from(["flip", "truncate", "length"]))
    if damage == "flip":
        index = draw(st.integers(4, len(packet) - 1))
        packet[index] ^= draw(st.integers(1, 255))
    elif damage == "truncate":
        packet = packet[: draw(st.integers(0, len(packet) - 1))]
    else:
        packet[5] = draw(st.integers(0, 255).filter(lambda v: v != packet[5]))
    return bytes(packet)


@FUZZ
@given(packet=damaged_packets(), cuts=st.lists(st.integers(0, 60), max_size=3))
def test_damaged_packets_get_no_reply(packet: bytes, cuts: list[int]) -> None:
    assume(not parse_packets(packet))
    chain = fresh_chain()
    assert feed(chain, packet, cuts) == []
    chain.advance(0.05)
    assert len(feed(chain, build_instruction(2, Instruction.PING), [])) == 1


@FUZZ
@given(
    servo_id=st.sampled_from([*IDS, 7, BROADCAST_ID]),
    instruction=st.one_of(st.sampled_from(list(Instruction)), st.integers(0, 255)),
    params=st.one_of(
        st.binary(max_size=40),
        st.lists(st.sampled_from([0, 1, 2, 3, 4, 0x74, 0x84, 0xFF]), max_size=24).map(bytes),
    ),
)
def test_any_valid_packet_is_answered_only_with_valid_status_packets(
    servo_id: int, instruction: int, params: bytes
) -> None:
    chain = fresh_chain()
    replies = chain.receive(build_instruction(servo_id, instruction, params))
    if instruction in (Instruction.FAST_SYNC_READ, Instruction.FAST_BULK_READ):
        packets = parse_packets(b"".join(r.data for r in replies))
        assert all(p.servo_id == BROADCAST_ID and p.is_status for p in packets)
        return
    for reply in replies:
        packets = parse_packets(reply.data)
        assert len(packets) == 1 and packets[0].is_status
        assert packets[0].servo_id in IDS
    if servo_id not in (*IDS, BROADCAST_ID):
        assert replies == []
