import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from snakebot.errors import MissingDependencyError, SnakebotError
from snakebot.servo_tables import (
    RegisterValueError,
    UnknownModelError,
    UnknownRegisterError,
    decode_signed,
    encode_value,
    loader,
    model_file_dir,
    supported_models,
    table_for_model,
)

MODELS = {
    "XL430-W250": ("xl430_w250", 1060),
    "XM430-W350": ("xm430_w350", 1020),
    "XL330-M288": ("xl330_m288", 1200),
}
# Addresses the e-Manual puts elsewhere than the SDK's xl330_m288.model (see xl330_m288.toml).
MODEL_FILE_FIXES = {
    ("XL330-M288", "Indirect Data 1"): 208,
    ("XL330-M288", "Indirect Data Write"): 208,
    ("XL330-M288", "Indirect Data Read"): 214,
}


def sdk_rows(stem: str) -> list[tuple[int, int, str]]:
    rows, in_table = [], False
    for line in (model_file_dir() / f"{stem}.model").read_text().splitlines():
        if line.startswith("["):
            in_table = line.strip() == "[control table]"
        elif in_table and line[:1].isdigit():
            address, size, name = line.split("\t")[:3]
            rows.append((int(address), int(size), name.strip()))
    return rows


def test_supported_models_cover_the_three_snake_servos() -> None:
    assert set(MODELS) <= set(supported_models())


@pytest.mark.parametrize("model", sorted(MODELS))
def test_every_sdk_model_file_item_is_in_the_table_at_its_address(model: str) -> None:
    table = table_for_model(model)
    rows = sdk_rows(MODELS[model][0])
    assert len(rows) > 40
    for address, size, name in rows:
        register = table[name]
        assert register.name == name
        assert register.size == size
        assert register.address == MODEL_FILE_FIXES.get((model, name), address), name


@pytest.mark.parametrize("model", sorted(MODELS))
@pytest.mark.parametrize(
    ("key", "address", "size"),
    [
        ("model_number", 0, 2),
        ("id", 7, 1),
        ("baud_rate", 8, 1),
        ("return_delay_time", 9, 1),
        ("drive_mode", 10, 1),
        ("operating_mode", 11, 1),
        ("homing_offset", 20, 4),
        ("velocity_limit", 44, 4),
        ("shutdown", 63, 1),
        ("torque_enable", 64, 1),
        ("status_return_level", 68, 1),
        ("hardware_error_status", 70, 1),
        ("bus_watchdog", 98, 1),
        ("profile_acceleration", 108, 4),
        ("profile_velocity", 112, 4),
        ("goal_position", 116, 4),
        ("realtime_tick", 120, 2),
        ("moving", 122, 1),
        ("present_velocity", 128, 4),
        ("present_position", 132, 4),
        ("present_input_voltage", 144, 2),
        ("present_temperature", 146, 1),
    ],
)
def test_well_known_addresses(model: str, key: str, address: int, size: int) -> None:
    register = table_for_model(model)[key]
    assert (register.address, register.size) == (address, size)


def test_xl430_reports_load_not_current_and_has_its_own_defaults() -> None:
    table = table_for_model("XL430-W250")
    load = table.by_address(126)
    assert load is not None and load.key == "present_load"
    assert (load.minimum, load.maximum, load.unit, load.scale, load.signed) == (
        -1000,
        1000,
        "%",
        0.1,
        True,
    )
    assert "current_limit" not in table and "goal_current" not in table
    defaults = {
        k: table[k].default
        for k in (
            "position_p_gain",
            "position_i_gain",
            "position_d_gain",
            "velocity_p_gain",
            "velocity_i_gain",
            "temperature_limit",
            "max_voltage_limit",
            "min_voltage_limit",
            "velocity_limit",
            "shutdown",
            "return_delay_time",
            "status_return_level",
        )
    }
    assert defaults == {
        "position_p_gain": 640,
        "position_i_gain": 0,
        "position_d_gain": 4000,
        "velocity_p_gain": 100,
        "velocity_i_gain": 1000,
        "temperature_limit": 72,
        "max_voltage_limit": 140,
        "min_voltage_limit": 60,
        "velocity_limit": 265,
        "shutdown": 52,
        "return_delay_time": 250,
        "status_return_level": 2,
    }
    assert table.specs.operating_modes == (1, 3, 4, 16)


def test_xm430_and_xl330_differ_where_the_emanual_says() -> None:
    xm, xl = table_for_model(1020), table_for_model(1200)
    assert (xm["current_limit"].address, xm["current_limit"].default) == (38, 1193)
    assert xm["current_limit"].scale == pytest.approx(0.00269)
    assert (xm["max_voltage_limit"].default, xm["min_voltage_limit"].default) == (160, 95)
    assert xm["velocity_limit"].default == 200 and xm["position_p_gain"].default == 800
    assert (xl["current_limit"].default, xl["shutdown"].default, xl["velocity_limit"].default) == (
        1750,
        53,
        445,
    )
    assert xl["pwm_slope"].address == 62 and 7 not in xl.baud_rates
    assert xl.specs.indirect_banks == ((168, 208, 20),)


def test_access_eeprom_and_sign_facts() -> None:
    table = table_for_model("XM430-W350")
    assert table["id"].eeprom and table["operating_mode"].eeprom and table["shutdown"].eeprom
    assert not table["torque_enable"].eeprom and not table["goal_position"].eeprom
    assert table["present_position"].access == "R" and table["goal_position"].access == "RW"
    assert table["model_number"].access == "R" and not table["model_number"].writable
    assert table["present_velocity"].signed and table["homing_offset"].signed
    assert not table["profile_velocity"].signed and not table["velocity_limit"].signed


def test_scales_are_si() -> None:
    table = table_for_model("XL430-W250")
    assert table["present_position"].scale == pytest.approx(2 * math.pi / 4096)
    assert table["present_position"].unit == "rad"
    assert table["present_velocity"].scale == pytest.approx(0.229 * 2 * math.pi / 60)
    assert table["present_velocity"].unit == "rad/s"
    assert table["return_delay_time"].to_si(250) == pytest.approx(500e-6)
    assert table["present_input_voltage"].to_si(111) == pytest.approx(11.1)
    assert table["goal_position"].from_si(math.pi) == 2048


def test_lookup_by_name_key_number_and_spelling() -> None:
    table = table_for_model("XL430-W250")
    assert table_for_model(1060) is table
    assert table_for_model("xl430_w250") is table and table_for_model("XL430-W250-T") is table
    assert table["Goal Position"] is table["goal_position"]
    assert table["Secondary(Shadow) ID"].key == "secondary_shadow_id"
    assert table.by_address(116) is table["goal_position"]
    assert table.by_address(117) is None
    assert table.protocol == 2.0 and table.model_number == 1060


def test_unknown_register_lists_close_names() -> None:
    table = table_for_model("XL430-W250")
    with pytest.raises(UnknownRegisterError) as caught:
        table["goal_positon"]
    assert isinstance(caught.value, KeyError) and isinstance(caught.value, SnakebotError)
    assert "goal_position" in str(caught.value)


def test_unknown_model_names_the_supported_ones() -> None:
    with pytest.raises(UnknownModelError, match="XL430-W250"):
        table_for_model("RX-28")
    with pytest.raises(UnknownModelError):
        table_for_model(9999)


def test_missing_sdk_names_the_install_command(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(loader.importlib.util, "find_spec", lambda name: None)
    with pytest.raises(MissingDependencyError, match="pip install"):
        model_file_dir()


def test_signed_decoding_and_encoding_examples() -> None:
    assert decode_signed(0xFFFFFFFF, 4) == -1
    assert decode_signed(0x7FFF, 2) == 32767 and decode_signed(0x8000, 2) == -32768
    assert decode_signed(0xFF, 1) == -1 and decode_signed(0x7F, 1) == 127
    assert encode_value(-1, 4) == b"\xff\xff\xff\xff"
    assert encode_value(512, 4) == b"\x00\x02\x00\x00"
    assert encode_value(255, 1) == b"\xff"
    with pytest.raises(RegisterValueError):
        encode_value(256, 1)
    with pytest.raises(RegisterValueError):
        encode_value(-129, 1)


@given(size=st.sampled_from([1, 2, 4]), data=st.data())
def test_encode_decode_round_trip(size: int, data: st.DataObject) -> None:
    value = data.draw(st.integers(-(1 << (8 * size - 1)), (1 << (8 * size - 1)) - 1))
    raw = int.from_bytes(encode_value(value, size), "little")
    assert decode_signed(raw, size) == value
