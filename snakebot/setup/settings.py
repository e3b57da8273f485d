"""The servo settings a robot wants: its servo file's ``[settings]``, robot and joint overrides.

Precedence, lowest first: ``servos/<model>.toml [settings]``, the robot file's ``[settings]``, a
joint's ``settings = {...}``. ID and Baud Rate come from the robot file (``[[joints]] servo_id``,
``[bus] baud``), Position P/I/D Gain from its ``[gains]``; the settings may not set them. The
wanted values are checked with the Dynamixel backend's own connect checks, so whatever
``snakebot config apply`` writes, ``snakebot run --backend dynamixel`` accepts.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from snakebot.backends.dynamixel.checks import LIMIT_KEYS, SETTINGS_KEYS, check_settings
from snakebot.backends.dynamixel.ticks import TickConverter
from snakebot.config.schema import JointConfig, RobotConfig
from snakebot.errors import ConfigError
from snakebot.servo_tables import Register, ServoTable, table_for_model
from snakebot.setup.units import Unit, UnitError, display, parse_key, to_raw

GAIN_KEYS = {"position_p_gain": "position_p", "position_i_gain": "position_i",
             "position_d_gain": "position_d"}
DERIVED = {
    "id": "comes from the robot file ([[joints]] servo_id)",
    "baud_rate": "comes from the robot file ([bus] baud)",
    **{key: f"comes from the robot file ([gains] {name})" for key, name in GAIN_KEYS.items()},
}
REFUSED = {
    "torque_enable": "is switched by the tools (off for EEPROM writes), not a setting",
    "protocol_type": "must stay 2: snakebot speaks Protocol 2.0 only",
    "led": "is a status light, not a setting",
}
REQUIRED = (*SETTINGS_KEYS, *LIMIT_KEYS)
REBOOT_KEYS = frozenset({"startup_configuration"})
"""Settings that take effect at boot (e-Manual Startup Configuration): apply reboots after them."""


@dataclass(frozen=True)
class Setting:
    """One wanted register value; ``unit`` is how the user wrote it, ``source`` where."""

    register: Register
    raw: int
    unit: Unit | None
    source: str
    table: ServoTable

    @property
    def key(self) -> str:
        """The register key, e.g. ``return_delay_time``."""
        return self.register.key

    @property
    def eeprom(self) -> bool:
        """Whether the register is in EEPROM (kept at power-off, writable only with torque off)."""
        return self.register.eeprom

    def show(self, raw: int) -> tuple[str, str]:
        """A register value as (value, unit) in the unit the setting was written in."""
        return display(self.register, self.unit, raw, self.table)


@dataclass(frozen=True)
class ServoSettings:
    """Everything one servo should hold, in address order."""

    joint: int
    servo_id: int
    settings: tuple[Setting, ...]

    def get(self, key: str) -> Setting:
        """The setting of register ``key`` (KeyError if none)."""
        for setting in self.settings:
            if setting.key == key:
                return setting
        raise KeyError(key)


@dataclass(frozen=True)
class ChainSettings:
    """The wanted settings of every servo of a robot, head to tail, and the bus they share."""

    robot: RobotConfig
    table: ServoTable
    baud: int
    servos: tuple[ServoSettings, ...]
    notes: tuple[str, ...] = ()

    def for_id(self, servo_id: int) -> ServoSettings:
        """The settings of the servo with ``servo_id``."""
        return next(s for s in self.servos if s.servo_id == servo_id)


def _read(path: Path) -> dict[str, Any]:
    try:
        with path.open("rb") as handle:
            return tomllib.load(handle)
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(path, "", f"cannot read: {exc}") from exc


def _entries(
    source: Path, where: str, data: object, table: ServoTable
) -> dict[str, Setting]:
    if not isinstance(data, Mapping):
        raise ConfigError(source, where, f"expected a table, got {type(data).__name__}")
    out: dict[str, Setting] = {}
    for key, value in data.items():
        path = f"{where}.{key}"
        try:
            register, unit = parse_key(table, key)
        except UnitError as exc:
            raise ConfigError(source, path, str(exc)) from None
        reason = DERIVED.get(register.key) or REFUSED.get(register.key)
        if register.key.startswith("goal_"):
            reason = "is a command, not a setting"
        if not register.writable:
            reason = "is read-only"
        if reason:
            raise ConfigError(source, path, f"{register.key} {reason}")
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(source, path, f"expected a number, got {value!r}")
        try:
            raw = to_raw(register, unit, value, table)
        except UnitError as exc:
            raise ConfigError(source, path, str(exc)) from None
        if not register.minimum <= raw <= register.maximum:
            low, high = (display(register, unit, r, table)[0] for r in
                         (register.minimum, register.maximum))
            raise ConfigError(source, path, f"{value} is outside {low}..{high} "
                              f"{unit.symbol if unit else '(raw)'} for {table.model}")
        if register.key in out:
            raise ConfigError(source, path, f"{register.key} is set twice in [{where}]")
        out[register.key] = Setting(register, raw, unit, f"{source.name} {path}", table)
    return out


def _derived(robot: RobotConfig, table: ServoTable, source: Path) -> dict[str, Setting]:
    try:
        baud_index = table.baud_index(robot.bus.baud)
    except ValueError as exc:
        raise ConfigError(source, "bus.baud", str(exc)) from None
    out = {"baud_rate": Setting(table["baud_rate"], baud_index, None, "[bus] baud", table)}
    for key, name in GAIN_KEYS.items():
        out[key] = Setting(table[key], getattr(robot.gains, name), None, f"[gains] {name}", table)
    return out


def load_settings(robot: RobotConfig) -> ChainSettings:
    """The settings ``robot`` wants on each servo; ConfigError naming file and key if invalid."""
    table = table_for_model(robot.servo.name)
    servo_file = robot.servo.source
    base = _entries(servo_file, "settings", _read(servo_file).get("settings", {}), table)
    robot_data = _read(robot.source)
    overrides = _entries(robot.source, "settings", robot_data.get("settings", {}), table)
    raw_joints = robot_data.get("joints", [])
    derived = _derived(robot, table, robot.source)
    servos = []
    for index, joint in enumerate(robot.joints):
        item = raw_joints[index] if index < len(raw_joints) else {}
        own = _entries(robot.source, f"joints[{index}].settings", item.get("settings", {}), table)
        merged = {**base, **overrides, **own, **derived}
        ordered = tuple(sorted(merged.values(), key=lambda s: s.register.address))
        servos.append(ServoSettings(index, joint.servo_id, ordered))
    chain = ChainSettings(robot, table, robot.bus.baud, tuple(servos))
    return _checked(chain, servo_file, robot.joints)


def _checked(
    chain: ChainSettings, servo_file: Path, joints: tuple[JointConfig, ...]
) -> ChainSettings:
    values: dict[int, dict[str, int]] = {}
    for servo in chain.servos:
        keys = {s.key: s.raw for s in servo.settings}
        missing = [k for k in REQUIRED if k not in keys]
        if missing:
            raise ConfigError(servo_file, "settings", f"missing {', '.join(missing)}: `snakebot "
                              "run --backend dynamixel` checks them at connect, so set them here")
        values[servo.servo_id] = keys
    ids = [j.servo_id for j in joints]
    errors, notes = check_settings(values, ids, TickConverter.for_robot(chain.robot))
    if errors:
        raise ConfigError(
            chain.robot.source, "settings", "`snakebot run --backend dynamixel` would refuse "
            "these settings: " + "; ".join(errors)
        )
    return ChainSettings(chain.robot, chain.table, chain.baud, chain.servos, tuple(notes))
