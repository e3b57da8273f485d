"""Protocol 1.0 control tables (AX, MX with P1 firmware): no .model file, addresses in the TOML."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from snakebot.servo_tables import (
    RegisterValueError,
    decode_magnitude,
    encode_magnitude,
    table_for_model,
)

# e-Manual ax-12a.md / mx-28.md control tables, as quoted in servo-families.md §3.2:
# key -> (address, size, factory default or None where the e-Manual gives "-").
AX_12A = {
    "model_number": (0, 2, 12),
    "firmware_version": (2, 1, None),
    "id": (3, 1, 1),
    "baud_rate": (4, 1, 1),
    "return_delay_time": (5, 1, 250),
    "min_position_limit": (6, 2, 0),
    "max_position_limit": (8, 2, 1023),
    "temperature_limit": (11, 1, 70),
    "min_voltage_limit": (12, 1, 60),
    "max_voltage_limit": (13, 1, 140),
    "max_torque": (14, 2, 1023),
    "status_return_level": (16, 1, 2),
    "alarm_led": (17, 1, 36),
    "shutdown": (18, 1, 36),
    "torque_enable": (24, 1, 0),
    "led": (25, 1, 0),
    "cw_compliance_margin": (26, 1, 1),
    "ccw_compliance_margin": (27, 1, 1),
    "cw_compliance_slope": (28, 1, 32),
    "ccw_compliance_slope": (29, 1, 32),
    "goal_position": (30, 2, None),
    "moving_speed": (32, 2, None),
    "torque_limit": (34, 2, None),
    "present_position": (36, 2, None),
    "present_velocity": (38, 2, None),
    "present_load": (40, 2, None),
    "present_input_voltage": (42, 1, None),
    "present_temperature": (43, 1, None),
    "registered_instruction": (44, 1, 0),
    "moving": (46, 1, 0),
    "lock": (47, 1, 0),
    "punch": (48, 2, 32),
}
MX_28 = {
    **{k: v for k, v in AX_12A.items() if "compliance" not in k},
    "model_number": (0, 2, 29),
    "baud_rate": (4, 1, 34),
    "max_position_limit": (8, 2, 4095),
    "temperature_limit": (11, 1, 80),
    "max_voltage_limit": (13, 1, 160),
    "multi_turn_offset": (20, 2, 0),
    "resolution_divider": (22, 1, 1),
    "position_d_gain": (26, 1, 0),
    "position_i_gain": (27, 1, 0),
    "position_p_gain": (28, 1, 32),
    "punch": (48, 2, 0),
    "realtime_tick": (50, 2, 0),
    "goal_acceleration": (73, 1, 0),
}


@pytest.mark.parametrize(("model", "expected"), [("AX-12A", AX_12A), ("MX-28", MX_28)])
def test_every_emanual_item_is_at_its_address_with_its_default(
    model: str, expected: dict[str, tuple[int, int, int | None]]
) -> None:
    table = table_for_model(model)
    assert set(table.registers) == set(expected)
    for key, (address, size, default) in expected.items():
        register = table[key]
        assert (register.address, register.size) == (address, size), key
        assert register.eeprom == (address < 24), key
        if default is not None:
            assert register.default == default, key


def test_role_keys_carry_the_datasheet_names() -> None:
    table = table_for_model("AX-12A")
    assert table["min_position_limit"].name == "CW Angle Limit"
    assert table["CCW Angle Limit"] is table["max_position_limit"]
    assert table["present_velocity"].name == "Present Speed"
    assert table.by_address(42) is table["present_input_voltage"]


def test_p1_model_facts() -> None:
    ax, mx = table_for_model("AX-12A"), table_for_model("MX-28")
    assert (ax.family, ax.protocols, ax.protocol) == ("dynamixel", (1.0,), 1.0)
    specs = ax.specs
    assert (specs.bulk_read, specs.fast_sync_read, specs.gains) == (False, False, "compliance")
    assert (mx.specs.bulk_read, mx.specs.gains) == (True, "pid")
    ticks = ax.specs.ticks
    assert (ticks.count, ticks.travel_deg, ticks.centre, ticks.maximum) == (1024, 300.0, 512, 1023)
    assert math.degrees(ticks.rad_per_tick) == pytest.approx(0.293, abs=1e-3)
    assert math.degrees(ax["goal_position"].scale) == pytest.approx(0.293, abs=1e-3)
    assert (mx.specs.ticks.count, mx.specs.ticks.centre) == (4096, 2048)
    assert (ax.specs.stall_torque_nm, mx.specs.stall_torque_nm) == (1.5, 2.5)
    assert ax.specs.no_load_speed_rad_s == pytest.approx(59 * 2 * math.pi / 60, rel=1e-3)


def test_baud_tables_follow_2mbps_over_value_plus_one() -> None:
    ax, mx = table_for_model("AX-12A"), table_for_model("MX-28")
    for value, rate in ax.baud_rates.items():
        assert rate == pytest.approx(2_000_000 / (value + 1), rel=0.03), value
    assert ax.baud_index(1_000_000) == 1 and ax.baud_index(57600) == 34
    assert mx.baud_rates[mx["baud_rate"].default] == 57600
    assert ax.baud_rates[ax["baud_rate"].default] == 1_000_000
    assert mx.baud_index(3_000_000) == 252
    with pytest.raises(RegisterValueError, match="AX-12A"):
        ax.baud_index(3_000_000)


def test_present_speed_and_load_are_sign_magnitude_bit_10() -> None:
    table = table_for_model("AX-12A")
    load, speed = table["present_load"], table["present_velocity"]
    assert (load.sign, load.sign_bit, load.signed) == ("magnitude", 10, False)
    # e-Manual "Present Load": 512 = 50 % CCW; 1024 + 512 = 50 % CW; 1024 equals 0.
    assert load.decode(bytes([0x00, 0x02])) == 512
    assert load.decode((1024 + 512).to_bytes(2, "little")) == -512
    assert load.decode((1024).to_bytes(2, "little")) == 0
    assert load.to_si(load.decode((1024 + 512).to_bytes(2, "little"))) == pytest.approx(-51.2)
    # e-Manual "Present Speed": 300 = 33.3 rpm CCW.
    assert speed.to_si(speed.value_of(300)) * 60 / (2 * math.pi) == pytest.approx(33.3, abs=0.05)
    assert speed.to_si(speed.value_of(1024 + 300)) < 0
    assert load.encode(-512) == (1024 + 512).to_bytes(2, "little")
    assert load.raw_of(-1) == 1025
    with pytest.raises(RegisterValueError):
        load.encode(1024)


def test_two_complement_registers_are_unchanged() -> None:
    mx = table_for_model("MX-28")
    offset = mx["multi_turn_offset"]
    assert offset.sign == "twos" and offset.decode(b"\xff\xff") == -1
    assert mx["goal_position"].encode(-28672) == (65536 - 28672).to_bytes(2, "little")


@given(bit=st.sampled_from([10, 11, 15]), data=st.data())
def test_sign_magnitude_round_trip(bit: int, data: st.DataObject) -> None:
    value = data.draw(st.integers(-((1 << bit) - 1), (1 << bit) - 1))
    raw = encode_magnitude(value, bit)
    assert 0 <= raw < 1 << (bit + 1)
    assert decode_magnitude(raw, bit) == value
