"""A Protocol 1.0 bus through the SDK's Protocol1PacketHandler, over a scripted port.

AX-12A: no group read, so the bus reads one servo at a time; MX-28: one Bulk Read. The status
byte's overload/overheating/input-voltage bits are the servo's condition (its data is good),
the others are errors of the instruction. Packets come from the emulator's P1 codec.
"""

from __future__ import annotations

import pytest

from snakebot.backends.chain.bus import ServoBus
from snakebot.backends.chain.faults import ServoStatusError, SyncReadError
from snakebot.emulation.protocol1 import build_instruction
from tests.unit.backends.chain.fakeport import ScriptedPort, status1

STATE = ("present_load", "present_velocity", "present_position")  # 36..41 on AX and MX


def block(position: int, speed_raw: int, load_raw: int) -> bytes:
    return (
        position.to_bytes(2, "little")
        + speed_raw.to_bytes(2, "little")
        + load_raw.to_bytes(2, "little")
    )


@pytest.fixture
def port() -> ScriptedPort:
    return ScriptedPort("fake1")


def bus_of(model: str, port: ScriptedPort) -> ServoBus:
    bus = ServoBus(
        "fake1",
        1_000_000,
        model=model,
        protocol=1.0,
        port_handler_factory=lambda name: port,
        retries=1,
    )
    bus.open()
    return bus


def test_an_ax_chain_is_read_one_servo_at_a_time_with_sign_magnitude_speed(
    port: ScriptedPort,
) -> None:
    bus = bus_of("AX-12A", port)
    assert bus.capabilities.read_method == "read"
    port.script = [status1(1, 0, block(512, 1024 + 5, 30)), status1(2, 0, block(700, 7, 1024 + 40))]
    values = bus.sync_read(STATE, [1, 2])
    assert port.written == [
        build_instruction(1, 0x02, bytes([36, 6])),
        build_instruction(2, 0x02, bytes([36, 6])),
    ]
    assert values[1] == {"present_position": 512, "present_velocity": -5, "present_load": 30}
    assert values[2] == {"present_position": 700, "present_velocity": 7, "present_load": -40}


def test_a_silent_ax_servo_is_named_and_the_others_are_kept(port: ScriptedPort) -> None:
    bus = bus_of("AX-12A", port)
    port.script = [
        status1(1, 0, block(512, 0, 0)),
        None,
        status1(1, 0, block(512, 0, 0)),
        None,
        None,
    ]
    with pytest.raises(SyncReadError) as info:
        bus.sync_read(STATE, [1, 2])
    assert info.value.missing_ids == (2,)
    assert info.value.partial[1]["present_position"] == 512


def test_an_mx_chain_is_read_by_one_bulk_read(port: ScriptedPort) -> None:
    bus = bus_of("MX-28", port)
    assert bus.capabilities.read_method == "bulk_read"
    port.script = [status1(1, 0, block(2048, 3, 0)) + status1(2, 0, block(1000, 1024 + 3, 0))]
    rows = bus.sync_read_plan(STATE, [1, 2]).read_rows()
    # e-Manual protocol1.md Bulk Read: 0x00, then (length, ID, address) per servo
    assert port.written == [build_instruction(0xFE, 0x92, bytes([0, 6, 1, 36, 6, 2, 36]))]
    assert rows == [(2048, 3, 0), (1000, -3, 0)]  # address order: position, speed, load
    assert bus.group_fallbacks == 0


def test_overload_in_the_status_byte_keeps_the_data_and_flags_the_servo(
    port: ScriptedPort,
) -> None:
    bus = bus_of("AX-12A", port)
    port.script = [status1(3, 0x24, bytes([41]))]  # overload + overheating
    assert bus.read(3, "present_temperature") == 41
    assert bus.alerts == {3}
    assert bus.family.status_errors(bus.conditions[3]) == ("overheating", "overload")
    port.script = [status1(3, 0, bytes([40]))]
    bus.read(3, "present_temperature")
    assert bus.alerts == set() and bus.conditions == {}


def test_a_range_error_is_an_error_of_the_instruction(port: ScriptedPort) -> None:
    bus = bus_of("AX-12A", port)
    port.script = [status1(3, 0x08)]
    with pytest.raises(ServoStatusError, match="Out of range"):
        bus.write(3, "led", 1)


def test_a_checksum_error_is_sent_again(port: ScriptedPort) -> None:
    bus = bus_of("AX-12A", port)
    port.script = [status1(3, 0x10), status1(3, 0)]
    bus.write(3, "led", 1)
    assert len(port.written) == 2 and port.written[0] == port.written[1]


def test_goals_go_out_in_one_protocol_1_sync_write(port: ScriptedPort) -> None:
    bus = bus_of("AX-12A", port)
    bus.sync_write_plan("goal_position", [1, 2]).write([512, 600])
    assert port.written == [
        build_instruction(0xFE, 0x83, bytes([30, 2, 1, 0x00, 0x02, 2, 0x58, 0x02]))
    ]


def test_a_milder_factory_reset_is_refused_where_the_family_resets_everything(
    port: ScriptedPort,
) -> None:
    bus = bus_of("AX-12A", port)
    with pytest.raises(ValueError, match="resets ID and baud rate too"):
        bus.factory_reset(1, keep="keep_id")
    assert port.written == []
