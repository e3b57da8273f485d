"""Rates setup and scan look at (each model's Baud Rate table); what families say for scans."""

from __future__ import annotations

import re

import pytest

from snakebot.cli.main import build_parser
from snakebot.families import family_named
from snakebot.servo_tables import table_for_model
from snakebot.setup.bauds import (
    baud_value,
    factory_baud,
    family_bauds,
    model_bauds,
    port_rate,
)
from snakebot.setup.scan import sweep_seconds


@pytest.mark.parametrize(
    ("servo_rate", "port"),
    [
        (57143, 57600),  # 2 000 000 / 35, an AX or MX at Baud Rate 34
        (117647, 115200),  # 2 000 000 / 17
        (1_000_000, 1_000_000),
        (400_000, None),  # 2 000 000 / 5: no rate the SDK's port handler opens is near
        (2_250_000, None),
    ],
)
def test_a_servo_rate_is_opened_at_the_nearest_port_rate(servo_rate: int, port: int | None) -> None:
    assert port_rate(servo_rate) == port


@pytest.mark.parametrize(
    ("model", "factory", "value_1m", "value_57600"),
    [
        ("AX-12A", 1_000_000, 1, 34),
        ("MX-28", 57600, 1, 34),
        ("XL430-W250", 57600, 3, 1),
    ],
)
def test_each_model_is_searched_at_its_own_rates_factory_first(
    model: str, factory: int, value_1m: int, value_57600: int
) -> None:
    table = table_for_model(model)
    assert factory_baud(table) == factory
    assert model_bauds(table)[0] == factory
    assert (baud_value(table, 1_000_000), baud_value(table, 57600)) == (value_1m, value_57600)


def test_a_rate_the_model_cannot_be_set_to_is_refused_naming_its_rates() -> None:
    with pytest.raises(ValueError, match="XL430-W250 does not support 500000 bit/s"):
        baud_value(table_for_model("XL430-W250"), 500_000)
    assert baud_value(table_for_model("AX-12A"), 500_000) == 3


def test_scan_help_names_the_rates_each_family_is_searched_at() -> None:
    scan = build_parser()._subparsers._group_actions[0].choices["scan"]  # type: ignore[union-attr]
    text = " ".join(scan.format_help().split())
    found = re.search(r"X series: ([\d, ]+); AX/MX also ([\d, ]+); Feetech ([\d, ]+)\)", text)
    assert found is not None, text
    x_part, p1_part, feetech_part = found.groups()
    x_rates = [int(r) for r in x_part.split(", ")]
    extra = {int(r) for r in p1_part.split(", ")}
    assert x_rates == list(family_bauds(family_named("dynamixel-p2")))
    assert set(family_bauds(family_named("dynamixel-p1"))) == set(x_rates) | extra
    feetech = [int(r) for r in feetech_part.split(", ")]
    assert feetech == list(family_bauds(family_named("feetech-sts")))
    assert feetech[0] == 1_000_000 and 76800 in feetech  # the factory rate first


def test_only_protocol_2_has_a_broadcast_ping_and_firmware_sits_where_its_tables_keep_it() -> None:
    p1, p2 = family_named("dynamixel-p1"), family_named("dynamixel-p2")
    assert (p1.broadcast_ping, p2.broadcast_ping) == (False, True)
    assert p1.firmware_address == table_for_model("AX-12A")["firmware_version"].address == 2
    assert p2.firmware_address == table_for_model("XL430-W250")["firmware_version"].address == 6
    assert p1.capabilities(table_for_model("AX-12A")).broadcast_ping is False


def test_a_full_protocol_1_sweep_costs_about_nine_seconds_a_rate() -> None:
    assert sweep_seconds(254, 1_000_000) == pytest.approx(8.66, abs=0.01)
    assert sweep_seconds(254, 57600) == pytest.approx(9.08, abs=0.01)
    assert sweep_seconds(20, 1_000_000) < 1.0
