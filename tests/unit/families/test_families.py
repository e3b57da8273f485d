"""The servo families: what each protocol can do, how its error byte reads, what it costs."""

from __future__ import annotations

import pytest

from snakebot.errors import ConfigError
from snakebot.families import (
    DynamixelProtocol1,
    DynamixelProtocol2,
    ServoFamily,
    WireCost,
    family_for,
    family_named,
)
from snakebot.servo_tables import table_for_model

P1, P2 = DynamixelProtocol1(), DynamixelProtocol2()


def test_an_x_series_servo_defaults_to_protocol_2_and_can_switch_to_1() -> None:
    table = table_for_model("XL430-W250")
    assert family_for(table) == P2
    assert family_for(table, 1.0) == P1
    assert family_for(table, 2) is not P1


def test_an_xl330_in_protocol_1_is_refused_naming_the_model_and_its_protocols() -> None:
    with pytest.raises(ConfigError, match=r"XL330-M288 servos speak Protocol 2\.0 only"):
        family_for(table_for_model("XL330-M288"), 1.0)


def test_protocol_2_has_every_group_read_and_the_x_series_registers() -> None:
    caps = P2.capabilities(table_for_model("XM430-W350"))
    assert caps.read_method == "fast_sync_read"
    assert caps.bus_watchdog and caps.hardware_error_status and caps.current_sensing
    assert caps.reboot and caps.broadcast_ping
    assert "keep_id_baud" in caps.factory_reset_options
    # An XL430 measures load, not current.
    assert not P2.capabilities(table_for_model("XL430-W250")).current_sensing


def test_protocol_1_on_an_x_series_servo_keeps_only_what_the_protocol_has() -> None:
    caps = P1.capabilities(table_for_model("XL430-W250"))
    assert not caps.sync_read and not caps.fast_sync_read and not caps.reboot
    assert not caps.broadcast_ping and not caps.indirect_addresses
    assert caps.read_method == "bulk_read"
    # The X map stays: the watchdog (98) and hardware error (70) sit below address 256.
    assert caps.bus_watchdog and caps.hardware_error_status
    assert caps.factory_reset_options == ("all",)


def test_the_protocol_1_error_byte_reads_bit_by_bit() -> None:
    # e-Manual protocol1.md: FF FF 01 02 24 D8 is an overload and overheating status.
    assert P1.status_errors(0x24) == ("overheating", "overload")
    assert P1.status_errors(0x00) == ()
    assert P1.status_errors(0x7F) == (
        "input voltage",
        "angle limit",
        "overheating",
        "range",
        "checksum",
        "overload",
        "instruction",
    )


def test_the_protocol_2_error_byte_is_a_number_plus_the_alert_bit() -> None:
    assert P2.status_errors(0x07) == ("access",)
    assert P2.status_errors(0x80) == ("alert",)
    assert P2.status_errors(0x86) == ("data limit", "alert")


@pytest.mark.parametrize(
    ("family", "method", "expected"),
    [
        # reference/servo-families.md §5: 12 servos at L = 6.
        (P1, "read", WireCost(240, 12, 12)),  # 20 B per servo, 2.40 ms at 1 Mbps
        (P1, "bulk_read", WireCost(187, 12, 1)),  # 3N + 7 = 43 B request + 12 x 12 B
        # Protocol 2.0: 14 + N request; 11 + L per status; fast: one 8 + N(L + 4) reply.
        (P2, "sync_read", WireCost(14 + 12 + 12 * 17, 12, 1)),
        (P2, "fast_sync_read", WireCost(14 + 12 + 8 + 12 * 10, 1, 1)),
    ],
)
def test_wire_costs_match_the_packet_layouts(
    family: ServoFamily, method: str, expected: WireCost
) -> None:
    assert family.read_cost(method, 12, 6) == expected


def test_sync_write_sizes() -> None:
    assert P1.sync_write_bytes(12, 2) == 44  # reference §5: 0.44 ms at 1 Mbps
    assert P2.sync_write_bytes(12, 4) == 14 + 12 * 5


def test_protocol_1_has_no_sync_read_to_cost() -> None:
    with pytest.raises(ValueError, match=r"Protocol 1\.0 has no sync read"):
        P1.read_cost("sync_read", 12, 6)


def test_families_are_found_by_name() -> None:
    assert family_named("dynamixel-p1") == P1
    with pytest.raises(ConfigError, match="known: dynamixel-p2, dynamixel-p1"):
        family_named("feetech")


def test_an_ax_12a_reads_one_servo_at_a_time_and_has_no_watchdog() -> None:
    table = table_for_model("AX-12A")
    assert family_for(table) == P1
    caps = P1.capabilities(table)
    assert caps.read_method == "read"  # no Sync Read in Protocol 1.0, no Bulk Read on an AX
    assert not caps.bus_watchdog and not caps.hardware_error_status
    assert not caps.current_sensing
    with pytest.raises(ConfigError, match=r"AX-12A servos speak Protocol 1\.0 only"):
        family_for(table, 2.0)


def test_an_mx_28_reads_by_bulk_read_on_protocol_1_and_fast_sync_on_its_2_0_firmware() -> None:
    assert P1.capabilities(table_for_model("MX-28")).read_method == "bulk_read"
    two = table_for_model("MX-28-2")
    assert family_for(two) == P2
    assert P2.capabilities(two).read_method == "fast_sync_read"
