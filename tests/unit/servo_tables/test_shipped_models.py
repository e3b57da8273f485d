"""Every shipped model loads and agrees with the SDK's .model file and with its e-Manual page."""

import math

import pytest

from snakebot.servo_tables import model_entries, model_file_dir, supported_models, table_for_model
from tests.unit.servo_tables.test_servo_tables import MODEL_FILE_FIXES, sdk_rows

# Model -> (.model stem or None for Protocol 1.0, model number, protocols): issue 21's models.
SHIPPED = {
    "AX-12A": (None, 12, (1.0,)),
    "AX-18A": (None, 18, (1.0,)),
    "MX-28": (None, 29, (1.0,)),
    "MX-64": (None, 310, (1.0,)),
    "MX-106": (None, 320, (1.0,)),
    "MX-28-2": ("mx_28", 30, (2.0, 1.0)),
    "MX-64-2": ("mx_64", 311, (2.0, 1.0)),
    "MX-106-2": ("mx_106", 321, (2.0, 1.0)),
    "XC330-M288": ("xc330_m288", 1240, (2.0,)),
    "XL330-M288": ("xl330_m288", 1200, (2.0,)),
    "XL430-W250": ("xl430_w250", 1060, (2.0, 1.0)),
    "2XL430-W250": ("2xl430_w250", 1090, (2.0, 1.0)),
    "XM430-W350": ("xm430_w350", 1020, (2.0, 1.0)),
    "XH430-W350": ("xh430_w350", 1000, (2.0, 1.0)),
    "XM540-W270": ("xm540_w270", 1120, (2.0, 1.0)),
}
FIXES = {
    **MODEL_FILE_FIXES,
    **{("XC330-M288", n): a for (m, n), a in MODEL_FILE_FIXES.items() if m == "XL330-M288"},
}


# Issue 22's Feetech models (tests/unit/servo_tables/test_feetech_models.py checks their facts).
FEETECH = ("STS3215", "STS3215-12V", "STS3250", "SCS0009")


def test_the_shipped_models_are_exactly_issue_21s_and_22s() -> None:
    assert set(supported_models()) == set(SHIPPED) | set(FEETECH)
    assert all(entry.shipped for entry in model_entries())


@pytest.mark.parametrize("model", sorted(SHIPPED))
def test_every_shipped_model_loads_with_sane_facts(model: str) -> None:
    table = table_for_model(model)
    _, number, protocols = SHIPPED[model]
    assert (table.model, table.model_number, table.protocols) == (model, number, protocols)
    assert table_for_model(number) is table
    assert table["model_number"].default == number
    assert table.family == "dynamixel"
    for register in table.registers.values():
        assert register.minimum <= register.maximum, register.key
        if register.writable:
            assert register.minimum <= register.default <= register.maximum, register.key
    # Factory ID 1 and a factory baud the table can name; position in radians at the tick size.
    assert table["id"].default == 1
    assert table["baud_rate"].default in table.baud_rates
    assert table["goal_position"].scale == pytest.approx(table.specs.ticks.rad_per_tick, rel=1e-6)
    assert table["present_position"].unit == "rad"
    specs = table.specs
    assert specs.stall_torque_nm > 0 and specs.no_load_speed_rad_s > 0
    assert specs.stall_current_a > 0 and specs.nominal_voltage_v >= 5.0


@pytest.mark.parametrize("model", sorted(m for m, (stem, _, _) in SHIPPED.items() if stem))
def test_every_sdk_model_file_item_is_at_its_address(model: str) -> None:
    stem = SHIPPED[model][0]
    assert stem is not None and (model_file_dir() / f"{stem}.model").is_file()
    table = table_for_model(model)
    for address, size, name in sdk_rows(stem):
        register = table[name]
        assert (register.name, register.size) == (name, size)
        assert register.address == FIXES.get((model, name), address), name


# Initial values from each model's e-Manual control table.
EMANUAL_DEFAULTS = {
    "XH430-W350": {"current_limit": 648, "velocity_limit": 130, "position_p_gain": 900},
    "XM540-W270": {"current_limit": 2047, "velocity_limit": 128, "external_port_mode_1": 3},
    "XC330-M288": {
        "current_limit": 2352,
        "velocity_limit": 350,
        "position_p_gain": 1100,
        "position_d_gain": 500,
        "max_voltage_limit": 70,
        "min_voltage_limit": 35,
    },
    "2XL430-W250": {
        "velocity_limit": 250,
        "position_d_gain": 2000,
        "velocity_i_gain": 1800,
        "temperature_limit": 72,
    },
    "MX-28-2": {"velocity_limit": 380, "position_p_gain": 850, "acceleration_limit": 32767},
    "MX-64-2": {"current_limit": 1941, "velocity_limit": 435},
    "MX-106-2": {"current_limit": 2047, "velocity_limit": 360},
    "AX-18A": {"temperature_limit": 75, "max_torque": 983},
    "MX-64": {"max_voltage_limit": 240, "baud_rate": 34},
    "MX-106": {"max_voltage_limit": 160, "drive_mode": 0},
}


@pytest.mark.parametrize("model", sorted(EMANUAL_DEFAULTS))
def test_factory_defaults_match_the_emanual(model: str) -> None:
    table = table_for_model(model)
    for key, value in EMANUAL_DEFAULTS[model].items():
        assert table[key].default == value, key


def test_current_sensing_and_its_units() -> None:
    assert table_for_model("XH430-W350")["present_current"].scale == 0.00269
    assert table_for_model("XC330-M288")["present_current"].scale == 0.001
    assert table_for_model("MX-64-2")["goal_current"].scale == 0.00336
    assert "present_current" not in table_for_model("MX-28-2")
    assert table_for_model("MX-28-2")["present_load"].scale == 0.1
    assert "present_current" not in table_for_model("2XL430-W250")
    # MX-64 P1 "Current" is offset binary (2048 = 0 A), so it is kept raw under its own key.
    current = table_for_model("MX-64")["current"]
    assert (current.address, current.size, current.unit) == (68, 2, "")
    torque = table_for_model("MX-106")["goal_torque"]
    assert (torque.address, torque.sign, torque.sign_bit) == (71, "magnitude", 10)
    assert torque.to_si(torque.decode((1024 + 100).to_bytes(2, "little"))) == pytest.approx(-0.45)


def test_datasheet_figures() -> None:
    rpm = 2 * math.pi / 60
    figures = {  # model: (stall N·m, no-load rpm, volts)
        "XC330-M288": (0.93, 81, 5.0),
        "XH430-W350": (3.4, 30, 12.0),
        "XM540-W270": (10.6, 30, 12.0),
        "2XL430-W250": (1.4, 57, 11.1),
        "AX-18A": (1.8, 97, 12.0),
        "MX-64": (6.0, 63, 12.0),
        "MX-106-2": (8.4, 45, 12.0),
    }
    for model, (torque, speed, volts) in figures.items():
        specs = table_for_model(model).specs
        assert specs.stall_torque_nm == torque
        assert specs.no_load_speed_rad_s == pytest.approx(speed * rpm, rel=1e-3)
        assert specs.nominal_voltage_v == volts
