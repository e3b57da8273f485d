"""One source of truth per servo fact, and the register <-> SI gain mapping built on it."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import pytest

import snakebot
from snakebot.config import load_robot
from snakebot.config.loader import load_servo_model
from snakebot.config.schema import COMPLIANCE_GAIN_KEYS, GainRegisters
from snakebot.errors import ConfigError
from snakebot.servo import (
    COMPLIANCE_SLOPES,
    FACTORY_BAUD,
    FACTORY_ID,
    GainMapping,
    centre_tick,
    rad_per_tick,
)
from snakebot.servo_tables import supported_models, table_for_model
from snakebot.types import PDGains
from tests.conftest import edit_robot

PACKAGE = Path(snakebot.__file__).resolve().parent
ROBOT_FILE = PACKAGE.parent / "firmware_configs" / "robots" / "snake12.toml"
SERVO_DIR = PACKAGE.parent / "firmware_configs" / "servos"
# Models the shipped servo files cover (a control table alone gives no twin physics or settings).
SERVO_MODELS = [m for m in supported_models() if (SERVO_DIR / f"{m.lower()}.toml").exists()]


@pytest.mark.parametrize("model", SERVO_MODELS)
def test_every_register_value_survives_the_trip_to_si_and_back(model: str) -> None:
    servo = load_servo_model(model, ROBOT_FILE)
    table = table_for_model(model)
    if servo.gain_kind == "compliance":  # AX: the seven Compliance Slope levels
        for level in COMPLIANCE_SLOPES:
            values = dict.fromkeys(COMPLIANCE_GAIN_KEYS, level)
            assert servo.gain_writes(servo.gains_from(values)) == values
        return
    mapping = servo.gain_mapping
    maxima = (table["position_p_gain"].maximum, table["position_d_gain"].maximum)
    assert (mapping.p_max, mapping.d_max) == maxima  # 16383 on X and MX 2.0, 254 on MX P1
    for register in range(mapping.p_max + 1):
        assert mapping.position_p(mapping.kp_nm_per_rad(register)) == register
        assert mapping.position_d(mapping.kd_nms_per_rad(register)) == register
        values = {"position_p_gain": register, "position_i_gain": 3, "position_d_gain": register}
        assert servo.gain_writes(servo.gains_from(values), position_i=3) == values


def test_the_xl430_mapping_is_the_datasheet_arithmetic() -> None:
    # KPP = P/128 on an output out of 2 x PWM Limit (885), at 1.4 N·m stall, 4096 ticks per turn.
    mapping = load_robot("snake12").servo.gain_mapping
    per_p = 1.4 * (4096 / (2 * math.pi)) / (256 * 885)
    assert mapping.kp_nm_per_rad(640) == pytest.approx(640 * per_p, rel=1e-12)
    assert mapping.kd_nms_per_rad(4000) == pytest.approx(4000 * per_p * 8 * 0.001, rel=1e-12)
    assert mapping.pd_gains(640, 4000) == load_robot("snake12").gains
    # Bit for bit the arithmetic (and its order) the twin used before gains were SI, so recorded
    # twin runs at the shipped gains replay identically.
    stall = 1.4 * (11.1 / 11.1)
    error_gain = (4096 / (2 * math.pi)) / (256.0 * 885)
    assert mapping.kp_nm_per_rad(640) == stall * error_gain * 640
    assert mapping.kd_nms_per_rad(4000) == stall * error_gain * (128.0 / 16.0) * 4000 * 0.001


def test_si_gains_round_and_clip_into_the_registers() -> None:
    mapping = GainMapping(1.4, 4096, 885, 256.0, 32.0, 0.001, p_max=16383, d_max=16383)
    assert mapping.registers(PDGains(mapping.kp_nm_per_rad(99.6), 0.0)) == (100, 0)
    assert mapping.registers(PDGains(1e9, 1e9)) == (16383, 16383)
    with pytest.raises(ValueError, match="kp_nm_per_rad"):
        PDGains(-1.0)
    with pytest.raises(ValueError, match="kd_nms_per_rad"):
        PDGains(1.0, math.nan)


def test_a_robot_file_in_si_loads_like_its_register_twin(config_dir: Path) -> None:
    registers = load_robot(config_dir / "robots" / "snake12.toml")
    kp, kd = registers.gains.kp_nm_per_rad, registers.gains.kd_nms_per_rad
    path = edit_robot(
        config_dir,
        "snake12",
        "position_p = 640\nposition_i = 0\nposition_d = 4000",
        f"kp_nm_per_rad = {kp!r}\nkd_nms_per_rad = {kd!r}\nposition_i = 7",
    )
    si = load_robot(path)
    assert si.gains == registers.gains
    assert si.gain_registers == GainRegisters(640, 7, 4000)
    assert si.position_i_gain == 7


def test_both_gain_forms_at_once_are_refused_naming_file_and_key(config_dir: Path) -> None:
    path = edit_robot(
        config_dir, "snake12", "position_d = 4000", "position_d = 4000\nkd_nms_per_rad = 0.1"
    )
    with pytest.raises(ConfigError) as info:
        load_robot(path)
    assert (info.value.source, info.value.key) == (str(path), "gains.kd_nms_per_rad")
    assert "not both" in str(info.value)


def test_without_gains_a_robot_gets_the_control_tables_factory_gains(config_dir: Path) -> None:
    path = edit_robot(
        config_dir, "snake12", "position_p = 640\nposition_i = 0\nposition_d = 4000", ""
    )
    text = path.read_text().replace("[gains]", "")
    path.write_text(text)
    robot = load_robot(path)
    table = table_for_model("XL430-W250")
    factory = tuple(table[f"position_{g}_gain"].default for g in "pid")
    assert factory == (640, 0, 4000)
    assert robot.gain_registers == GainRegisters(*factory)


@pytest.mark.parametrize("model", SERVO_MODELS)
def test_the_datasheet_facts_come_from_the_control_table(model: str) -> None:
    servo = load_servo_model(model, ROBOT_FILE)
    table = table_for_model(model)
    physics = servo.physics
    assert servo.model_number == table.model_number
    assert physics.stall_torque_nm == table.specs.stall_torque_nm
    assert physics.no_load_speed_rad_s == table.specs.no_load_speed_rad_s
    assert physics.nominal_voltage_v == table.specs.nominal_voltage_v
    assert physics.ticks == table.specs.ticks
    # 4096 a turn centred at 2048 (X, MX, STS); 1024 over 300 deg centred at 512 (AX, SCS0009).
    assert centre_tick(physics.ticks) == (512 if model.startswith(("AX", "SCS")) else 2048)
    # The position registers' SI scale (what the emulator and the bus tables use) is the same
    # tick as the tick <-> radian formula's (the P1 tables write it to 8 digits).
    for key in ("goal_position", "present_position", "homing_offset", "multi_turn_offset"):
        if key in table:
            assert table[key].scale == pytest.approx(rad_per_tick(physics.ticks), rel=1e-7)
    # What a servo answers as from the factory: the ID and Baud Rate registers' defaults (an AX
    # leaves the factory at 1 Mbps, e-Manual ax-12a.md; a Feetech servo too, memory-sts.md).
    assert table["id"].default == FACTORY_ID
    one_mbps = model.startswith("AX") or table.family == "feetech"
    factory_baud = 1_000_000 if one_mbps else FACTORY_BAUD
    assert table.baud_rates[table["baud_rate"].default] == factory_baud


# Numbers that are servo facts: resolution and centre tick, gain register maximum, factory baud,
# model numbers, datasheet torques and speeds. Outside snakebot/servo and the control-table data
# they may appear in comments and docstrings, never as code.
FACTS = {4096, 2048, 16383, 57600, 1020, 1060, 1200, 885, 0.088, 5.969, 10.79, 4.817, 0.52, 4.1}
HOMES = {"servo", "servo_tables"}
NOT_FACTS = {
    ("snakebot/emulation/pty_server.py", 4096),  # a read buffer's size in bytes
    ("snakebot/cli/rl_cmd.py", 2048),  # PPO's rollout length in env steps (SB3's default)
    ("snakebot/rl/train.py", 2048),  # the same
    ("snakebot/rl/resume.py", 2048),  # the same, for a policy.json that records none
    ("snakebot/config/input_file.py", 4096),  # the longest string a config file may hold
    ("snakebot/setup/bauds.py", 57600),  # the rate below which a baud search looks last
}


def _numbers(tree: ast.AST) -> list[tuple[int, float]]:
    """Numeric literals, except inside a list/tuple of 3+ numbers (a table of rates, not a fact)."""
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Tuple | ast.List) and len(node.elts) >= 3:
            skip.update(id(e) for e in node.elts)
    return [
        (node.lineno, node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant)
        and type(node.value) in (int, float)
        and id(node) not in skip
    ]


def test_no_servo_fact_has_a_second_copy_in_the_code() -> None:
    copies = [
        f"{path.relative_to(PACKAGE.parent)}:{line}: {value}"
        for path in sorted(PACKAGE.rglob("*.py"))
        if path.relative_to(PACKAGE).parts[0] not in HOMES
        for line, value in _numbers(ast.parse(path.read_text(encoding="utf-8")))
        if value in FACTS and (path.relative_to(PACKAGE.parent).as_posix(), value) not in NOT_FACTS
    ]
    assert copies == []


def test_the_scan_finds_a_copy_when_there_is_one() -> None:
    assert _numbers(ast.parse("centre = 2048\nrates = (9600, 57600, 115200)")) == [(1, 2048)]
