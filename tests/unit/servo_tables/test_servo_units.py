from __future__ import annotations

import math

import pytest

from snakebot.servo_tables import table_for_model
from snakebot.servo_tables.units import UnitError, display, from_raw, parse_key, to_raw

TABLE = table_for_model("XL430-W250")


@pytest.mark.parametrize(
    ("key", "value", "raw", "shown"),
    [
        ("return_delay_time_us", 0, 0, ("0", "us")),
        ("return_delay_time_us", 500, 250, ("500", "us")),
        ("return_delay_time", 250, 250, ("250", "")),
        ("bus_watchdog_ms", 100, 5, ("100", "ms")),
        ("max_voltage_limit_v", 12.0, 120, ("12", "V")),
        ("temperature_limit_c", 70, 70, ("70", "degC")),
        ("pwm_limit_pct", 50, 442, ("49.946", "%")),
        ("velocity_limit_rpm", 22.9, 100, ("22.9", "rpm")),
        ("max_position_limit_deg", 90, 3072, ("90", "deg")),
        ("min_position_limit_deg", -90, 1024, ("-90", "deg")),
        ("min_position_limit_rad", 0.0, 2048, ("0", "rad")),
        ("homing_offset_deg", -45, -512, ("-45", "deg")),
    ],
)
def test_values_convert_from_the_users_unit(
    key: str, value: float, raw: int, shown: tuple[str, str]
) -> None:
    register, unit = parse_key(TABLE, key)
    assert to_raw(register, unit, value, TABLE) == raw
    assert display(register, unit, raw, TABLE) == shown
    if unit is not None:
        assert from_raw(register, unit, raw, TABLE) == pytest.approx(value, rel=2e-3, abs=0.1)


def test_baud_rate_is_shown_in_bits_per_second() -> None:
    register, unit = parse_key(TABLE, "baud_rate")
    assert display(register, unit, 3, TABLE) == ("1000000", "bit/s")


@pytest.mark.parametrize(
    ("key", "message"),
    [
        ("return_delay_time_v", "return_delay_time is in s; _v does not fit"),
        ("operating_mode_ms", r"a raw number \(no unit\); _ms does not fit"),
        ("retrun_delay_time_us", "did you mean"),
        ("Return Delay Time", "alias"),
    ],
)
def test_bad_keys_say_why(key: str, message: str) -> None:
    with pytest.raises(UnitError, match=message):
        parse_key(TABLE, key)


def test_raw_values_must_be_whole() -> None:
    register, unit = parse_key(TABLE, "shutdown")
    with pytest.raises(UnitError, match="whole raw register value"):
        to_raw(register, unit, 52.5, TABLE)
    assert to_raw(register, unit, 52.0, TABLE) == 52
    assert math.isclose(from_raw(register, unit, 52, TABLE), 52.0)


def test_a_value_no_register_can_hold_is_a_unit_error_not_an_overflow() -> None:
    # Found by the config fuzz: min_position_limit_rad = 1.58e307 raised OverflowError (exit 3).
    register, unit = parse_key(TABLE, "min_position_limit_rad")
    with pytest.raises(UnitError, match=r"min_position_limit.*far outside"):
        to_raw(register, unit, 1.5800037318125823e307, TABLE)
