"""The bus on Feetech servos through scservo_sdk and the emulator, register by register: a SYNC
WRITE of goals, a SYNC_READ of position, speed, load, voltage, temperature and current (STS3215),
one READ per servo on the big-endian SCS0009, sign-magnitude values decoded in one place (the
model data), and the SDK's result codes turned into the chain's (a silent servo is named)."""

from __future__ import annotations

import pytest
import scservo_sdk as scs

from snakebot.backends.chain.bus import ServoBus
from snakebot.backends.chain.faults import SyncReadError
from snakebot.backends.dynamixel import sdk
from snakebot.backends.feetech.sdk import FeetechLink
from snakebot.emulation import EmulatedChain, make_chain_for_ids, registered
from snakebot.emulation.port_feetech import EmulatedScsPortHandler

IDS = tuple(range(1, 13))
STATE = (
    "present_position",
    "present_velocity",
    "present_load",
    "present_input_voltage",
    "present_temperature",
    "present_current",
)


def settle(bus: ServoBus, chain: EmulatedChain, seconds: float) -> None:
    for _ in range(round(seconds / 0.01)):
        chain.advance(0.01)


@pytest.mark.parametrize("model", ["STS3215", "SCS0009"])
def test_goals_out_and_state_back_match_the_servos(model: str) -> None:
    chain = make_chain_for_ids(model, IDS, 1_000_000)
    with registered(chain) as url:
        bus = ServoBus(url, 1_000_000, model=model)
        with bus:
            assert isinstance(bus._link, FeetechLink)
            assert bus.ping(1) == bus.table.model_number
            centre = bus.table.specs.ticks.centre
            # Half the chain turns below the centre, half above: speeds of both signs.
            goals = {i: centre + (150 if i % 2 else -150) for i in IDS}
            bus.sync_write("torque_enable", dict.fromkeys(IDS, 1))
            bus.sync_write("goal_position", goals)
            assert {s.servo_id: s.peek("goal_position") for s in chain.servos} == goals
            settle(bus, chain, 0.02)
            keys = tuple(k for k in STATE if k in bus.table)
            moving = bus.sync_read(keys, list(IDS))
            # Odd IDs turn up, even ones down: speeds (and loads) of both signs, bit 15 decoded.
            for i in IDS:
                sign = 1 if i % 2 else -1
                assert sign * moving[i]["present_velocity"] > 0, i
                assert sign * (moving[i]["present_position"] - centre) > 0, i
            settle(bus, chain, 2.0)
            still = bus.sync_read(keys, list(IDS))
            truth = {s.servo_id: {k: s.peek(k) for k in keys} for s in chain.servos}
            assert still == truth  # at rest: what the bus read is what the servos hold
            assert all(abs(still[i]["present_position"] - goals[i]) <= 2 for i in IDS)
    if model == "STS3215":
        assert "present_current" in keys and bus.capabilities.read_method == "sync_read"
    else:  # SCS: no current sensing, no Sync Read, big-endian words
        assert "present_current" not in keys and bus.capabilities.read_method == "read"
        assert bus.table["present_position"].byteorder == "big"


@pytest.mark.parametrize("model", ["STS3215", "SCS0009"])
def test_a_silent_servo_is_named_after_the_retries(model: str) -> None:
    chain = make_chain_for_ids(model, IDS, 1_000_000)
    chain.silence(7)
    with registered(chain) as url:
        bus = ServoBus(url, 1_000_000, model=model)
        with bus, pytest.raises(SyncReadError) as info:
            bus.sync_read(("present_position",), list(IDS))
    assert info.value.missing_ids == (7,)
    assert sorted(info.value.partial) == [i for i in IDS if i != 7]
    assert "There is no status packet" in str(info.value) or "servo(s) 7" in str(info.value)


def stock_sync_read(url: str, address: int, size: int) -> dict[int, list[int] | None]:
    """What the stock SDK's own GroupSyncRead finds for each ID (error byte, then the block)."""
    port = EmulatedScsPortHandler(url)
    assert port.setBaudRate(1_000_000)
    group = scs.GroupSyncRead(scs.sms_sts(port), address, size)
    for servo_id in IDS:
        group.addParam(servo_id)
    assert group.txRxPacket() == scs.COMM_SUCCESS
    port.closePort()
    return dict(group.data_dict)


def test_the_one_pass_sync_read_finds_what_the_sdk_search_finds() -> None:
    """The link checks a whole SYNC_READ reply in one pass; it must hand out exactly what the
    SDK's byte-by-byte search (rxPacket/readRx) finds in the same reply, status bytes too."""
    chain = make_chain_for_ids("STS3215", IDS, 1_000_000)
    for servo in chain.servos:  # distinct values, some negative (bit 15), a status bit
        servo.poke("homing_offset", 40 * servo.servo_id - 200)
    chain.latch_hardware_error(5, 0x20)
    with registered(chain) as url:
        bus = ServoBus(url, 1_000_000, model="STS3215")
        with bus:
            reader = bus._link.sync_reader(56, 15, IDS)
            assert reader.transact(False) == sdk.COMM_SUCCESS
            mine = {i: [reader.error(i), *reader.data(i)] for i in IDS}
            joined = reader.joined()
        theirs = stock_sync_read(url, 56, 15)
    assert mine == theirs
    assert mine[5][0] == 0x20 and not any(mine[i][0] for i in IDS if i != 5)
    assert joined == bytes(b for i in IDS for b in theirs[i] or [])
    assert type(joined) is bytes  # the one-pass result (the SDK search's rows join to bytearray)


def test_a_corrupt_reply_falls_back_to_the_sdk_search_and_keeps_the_others() -> None:
    """One servo's status packet corrupt: the one-pass check refuses the reply, the SDK's own
    search still finds the eleven good packets, and the cycle's row set is refused whole."""
    chain = make_chain_for_ids("STS3215", IDS, 1_000_000)
    chain.corrupt_replies(4, next_n=1)
    with registered(chain) as url:
        bus = ServoBus(url, 1_000_000, model="STS3215")
        with bus:
            reader = bus._link.sync_reader(56, 15, IDS)
            result = reader.transact(False)
            found = [i for i in IDS if reader.available(i)]
            assert reader.joined() is None
            assert 4 not in found and len(found) == 11, (result, found)
            assert reader.transact(False) == sdk.COMM_SUCCESS  # the next read is whole again
            assert reader.joined() is not None and all(reader.available(i) for i in IDS)
