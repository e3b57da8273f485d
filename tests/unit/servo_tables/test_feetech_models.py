"""The Feetech models as data: Feetech's memory tables (ftservo-wiki memory-sts.md and
memory-scscl.md), its baud table, the sign-magnitude bits and each datasheet's figures."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from snakebot.errors import ConfigError
from snakebot.families import FeetechSCS, FeetechSTS, family_for
from snakebot.servo_tables import table_for_model
from snakebot.servo_tables.loader import build_table
from snakebot.servo_tables.models import model_entries

STS = ("STS3215", "STS3215-12V", "STS3250")
# Feetech's baud index (memory-sts.md, FTServo_Python SMS_STS_*), not LeRobot's (5 = 57600).
FEETECH_BAUDS = {
    0: 1_000_000,
    1: 500_000,
    2: 250_000,
    3: 128_000,
    4: 115_200,
    5: 76_800,
    6: 57_600,
    7: 38_400,
}


@pytest.mark.parametrize("model", STS)
def test_sts_table_is_feetechs_memory_table(model: str) -> None:
    table = table_for_model(model)
    assert table.family == "feetech" and table.protocols == (0.0,)
    assert family_for(table) == FeetechSTS()
    where = {key: (table[key].address, table[key].size) for key in table.registers}
    assert where["id"] == (5, 1) and where["baud_rate"] == (6, 1)
    assert where["min_position_limit"] == (9, 2) and where["max_position_limit"] == (11, 2)
    assert where["position_p_gain"] == (21, 1) and where["position_i_gain"] == (23, 1)
    assert where["homing_offset"] == (31, 2) and where["operating_mode"] == (33, 1)
    assert where["torque_enable"] == (40, 1) and where["goal_position"] == (42, 2)
    assert where["torque_limit"] == (48, 2) and where["lock"] == (55, 1)
    assert where["present_position"] == (56, 2) and where["present_load"] == (60, 2)
    assert where["present_input_voltage"] == (62, 1) and where["present_current"] == (69, 2)
    assert where["status"] == (65, 1)
    # EEPROM below 40, RAM from Torque Enable on; Lock powers up 1 (EEPROM writes not saved).
    assert table["homing_offset"].eeprom and not table["torque_enable"].eeprom
    assert table["lock"].default == 1 and table["status_return_level"].maximum == 1
    assert table.baud_rates == FEETECH_BAUDS and table["baud_rate"].default == 0
    assert table["id"].default == 1
    assert table.specs.position_mode == 0 and table["operating_mode"].default == 0


def test_sign_magnitude_bits_decode_as_feetech_documents() -> None:
    table = table_for_model("STS3215")
    # Position/speed bit 15, load bit 10, offset bit 11 (memory-sts.md, LeRobot's encodings).
    assert table["present_position"].sign_bit == 15 and table["goal_position"].sign_bit == 15
    assert table["present_velocity"].sign_bit == 15 and table["present_load"].sign_bit == 10
    assert table["homing_offset"].sign_bit == 11
    assert table["present_position"].value_of(0x8000 | 5) == -5  # not 32763 (lerobot#2223)
    assert table["present_load"].value_of(1024 + 300) == -300
    assert table["homing_offset"].raw_of(-100) == 2048 + 100
    assert (table["homing_offset"].minimum, table["homing_offset"].maximum) == (-2047, 2047)
    assert table.specs.ticks.sign == "magnitude" and table.specs.ticks.count == 4096
    # 50 steps/s per Goal Speed unit (0.732 rpm); 6.5 mA per Present Current unit.
    assert table["present_velocity"].scale == pytest.approx(50 * 2 * math.pi / 4096, rel=1e-6)
    assert table["present_current"].to_si(100) == pytest.approx(0.65)


def test_scs0009_is_a_big_endian_table_without_sync_read_or_current() -> None:
    table = table_for_model("SCS0009")
    family = family_for(table)
    assert family == FeetechSCS() and family.byte_order == "big"
    assert not family.capabilities(table).sync_read
    assert family.capabilities(table).read_method == "read"
    assert table["lock"].address == 48 and table["byte_order"].default == 1
    assert "present_current" not in table and "homing_offset" not in table
    assert "operating_mode" not in table
    assert (table["min_position_limit"].default, table["max_position_limit"].default) == (20, 1003)
    ticks = table.specs.ticks
    assert (ticks.count, ticks.travel_deg, ticks.centre) == (1024, 300.0, 512)


def test_datasheet_figures() -> None:
    rpm = 2 * math.pi / 60
    figures = {  # model: (stall N·m, no-load rpm, volts, model number)
        # 19.5 kg·cm, 0.238 s/60° at 6 V (ST-3215-C001), at its rated 7.4 V (x 7.4 / 6): 52 rpm
        "STS3215": (2.36, 52.0, 7.4, 777),
        "STS3215-12V": (2.94, 45.0, 12.0, 777),  # 30 kg·cm at 12 V (ST-3215-C018)
        "STS3250": (4.9, 75.0, 12.0, 2825),  # 50 kg·cm at 12 V
        "SCS0009": (0.23, 100.0, 6.0, 1284),  # 2.3 kg·cm, 0.1 s/60° at 6 V
    }
    for model, (torque, speed, volts, number) in figures.items():
        table = table_for_model(model)
        specs = table.specs
        assert specs.stall_torque_nm == torque
        assert specs.no_load_speed_rad_s == pytest.approx(speed * rpm, rel=2e-3)
        assert specs.nominal_voltage_v == volts
        assert table.model_number == number and table["model_number"].default == number


def test_the_12v_version_shares_777_but_is_found_by_name_only() -> None:
    assert table_for_model(777).model == "STS3215"
    assert table_for_model("STS3215-12V").model == "STS3215-12V"
    entry = next(e for e in model_entries() if e.name == "STS3215-12V")
    assert entry.variant_of == "STS3215"


def test_a_feetech_model_cannot_list_a_dynamixel_protocol(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(
        '[model]\nbase = "_feetech_sts"\nname = "X"\nmodel_number = 9\nprotocols = [2.0]\n'
    )
    with pytest.raises(ConfigError, match=r"model\.protocols.*0\.0 and/or 1\.0"):
        build_table(path)
