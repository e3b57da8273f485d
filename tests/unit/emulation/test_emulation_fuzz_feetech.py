"""Random and malformed byte streams on Feetech servos: the chain never raises, a damaged frame
gets silence (no status bit could say what was wrong), and every reply is one status packet."""

from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from snakebot.emulation import EmulatedChain, VirtualServo
from snakebot.emulation.protocol_feetech import (
    BROADCAST_ID,
    Instruction,
    build_instruction,
    parse_packets,
)

IDS = [1, 2, 3]
FUZZ = settings(
    max_examples=200, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow]
)


def fresh_chain() -> EmulatedChain:
    """Two STS3215s and an SCS0009 (both byte orders)."""
    models = {1: "STS3215", 2: "STS3215", 3: "SCS0009"}
    return EmulatedChain([VirtualServo(models[i], i, baud=1_000_000) for i in IDS], baud=1_000_000)


def feed(chain: EmulatedChain, data: bytes, cuts: list[int]) -> list[bytes]:
    out, start = [], 0
    for cut in [*sorted(set(cuts)), len(data)]:
        out += [r.data for r in chain.receive(data[start:cut])]
        start = max(start, cut)
    return out


header_pieces = st.sampled_from([b"\xff\xff", b"\xff\xff\x01", b"\xff", b"\xfe", b"\x00"])
biased_bytes = st.lists(st.one_of(header_pieces, st.binary(max_size=16)), max_size=24).map(b"".join)


@FUZZ
@given(data=biased_bytes, cuts=st.lists(st.integers(0, 200), max_size=5))
def test_garbage_gets_no_reply(data: bytes, cuts: list[int]) -> None:
    assume(not parse_packets(data))
    assert feed(fresh_chain(), data, cuts) == []


@FUZZ
@given(
    servo_id=st.sampled_from([*IDS, 7, BROADCAST_ID]),
    instruction=st.one_of(st.sampled_from(list(Instruction)), st.integers(0, 255)),
    params=st.one_of(
        st.binary(max_size=40),
        st.lists(st.sampled_from([0, 1, 2, 3, 5, 40, 42, 55, 56, 128, 0xFF]), max_size=24).map(
            bytes
        ),
    ),
)
def test_any_valid_packet_is_answered_only_with_status_packets_of_the_ids_on_the_bus(
    servo_id: int, instruction: int, params: bytes
) -> None:
    chain = fresh_chain()
    replies = chain.receive(build_instruction(servo_id, instruction, params))
    for reply in replies:
        packets = parse_packets(reply.data)
        if servo_id == BROADCAST_ID and instruction == Instruction.PING:
            continue  # every servo answers at once: a collision
        assert len(packets) == 1
        assert packets[0].servo_id in IDS
        assert packets[0].first & 0x80 == 0
    if servo_id not in (*IDS, BROADCAST_ID):
        assert replies == []
    chain.advance(0.05)
    # Whatever it did, the chain still answers a ping of a servo whose ID it did not change.
    survivors = [s.servo_id for s in chain.servos if s.baud == chain.baud]
    if survivors:
        assert feed(chain, build_instruction(survivors[0], Instruction.PING), [])
