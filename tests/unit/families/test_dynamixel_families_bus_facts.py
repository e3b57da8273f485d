"""The protocol facts the bus asks the Dynamixel families: which status bits are the servo's
condition, which error is worth sending again, and what a cycle's read costs on the wire."""

from __future__ import annotations

from snakebot.emulation.protocol import build_fast_status
from snakebot.families import WireCost, family_named

P1 = family_named("dynamixel-p1")
P2 = family_named("dynamixel-p2")


def test_protocol_2_alert_is_a_condition_and_crc_is_resent() -> None:
    assert P2.instruction_error(0x80) == 0
    assert P2.instruction_error(0x84) == 0x04  # data range, with the alert
    assert P2.resend_error == 0x03 and P2.access_error == 0x07
    assert P2.factory_reset_takes_option


def test_protocol_1_overload_heat_and_voltage_are_conditions_the_rest_errors() -> None:
    assert P1.instruction_error(0x25) == 0  # input voltage, overheating, overload
    assert P1.instruction_error(0x2A) == 0x0A  # angle limit + range, with an overload
    assert P1.status_errors(P1.instruction_error(0x2A)) == ("angle limit", "range")
    assert P1.resend_error == 0x10 and P1.access_error is None  # checksum; no access error
    assert not P1.factory_reset_takes_option


def test_a_fast_sync_read_reply_is_as_long_as_the_emulator_builds_it() -> None:
    for n in (1, 2, 12):
        reply = len(build_fast_status([(i + 1, 0, bytes(10)) for i in range(n)]))
        assert P2.read_cost("fast_sync_read", n, 10) == WireCost(14 + n + reply, 1, 1)
