"""Servo settings tables (``[settings]`` of servo and robot files, ``joints[].settings``): each key
a control-table register, optionally with a unit suffix, each value inside the register's range.

The robot-file loader checks every settings table with :func:`parse_settings` so that ``run`` and
``model`` refuse what ``config diff`` would; snakebot.setup.settings merges them per servo and
checks the result against what ``run --backend dynamixel`` accepts at connect.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from snakebot.config.fields import read_toml
from snakebot.errors import ConfigError
from snakebot.servo_tables import Register, ServoTable
from snakebot.servo_tables.units import Unit, UnitError, display, parse_key, to_raw

GAIN_KEYS = {
    "position_p_gain": "position_p",
    "position_i_gain": "position_i",
    "position_d_gain": "position_d",
    "cw_compliance_slope": "compliance_slope",
    "ccw_compliance_slope": "compliance_slope",
}
"""The position-loop registers (P/I/D Gain, or an AX's Compliance Slope) -> their [gains] key."""
DERIVED = {
    "id": "comes from the robot file ([[joints]] servo_id)",
    "baud_rate": "comes from the robot file ([bus] baud)",
    **{key: f"comes from the robot file ([gains] {name})" for key, name in GAIN_KEYS.items()},
}
REFUSED = {
    "torque_enable": "is switched by the tools (off for EEPROM writes), not a setting",
    "protocol_type": "is not a setting: the robot file's [bus] protocol says which protocol the "
    "bus speaks; switch an X-series servo's Protocol Type with Dynamixel Wizard 2.0 (a servo "
    "that changed protocol in the middle of config apply would stop answering it)",
    "led": "is a status light, not a setting",
    "lock": "is never written: a locked EEPROM (Lock = 1, AX and MX) takes no more writes "
    "until the servo is power-cycled",
}


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


def parse_settings(source: Path, where: str, data: object, table: ServoTable) -> dict[str, Setting]:
    """The settings table ``data`` found at key path ``where`` of ``source``, by register key.

    ConfigError naming ``source`` and ``where.<key>`` for a key that names no register (or a
    unit that does not fit it), a register the tools own (ID, baud, gains, torque), a read-only
    or command register, a value that is not a number or outside the register's range, or a
    register set twice.
    """
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
        if not math.isfinite(value):
            raise ConfigError(source, path, f"expected a finite number, got {value!r}")
        try:
            raw = to_raw(register, unit, value, table)
        except UnitError as exc:
            raise ConfigError(source, path, str(exc)) from None
        if not register.minimum <= raw <= register.maximum:
            low, high = (
                display(register, unit, r, table)[0] for r in (register.minimum, register.maximum)
            )
            raise ConfigError(
                source,
                path,
                f"{value} is outside {low}..{high} "
                f"{unit.symbol if unit else '(raw)'} for {table.model}",
            )
        if register.key in out:
            raise ConfigError(source, path, f"{register.key} is set twice in [{where}]")
        out[register.key] = Setting(register, raw, unit, f"{source.name} {path}", table)
    return out


def joint_settings(
    servo_file: Path, robot_file: Path, joint_count: int, table: ServoTable
) -> list[dict[str, Setting]]:
    """Each joint's settings, head to tail, as the files give them: the servo file's
    ``[settings]``, overridden by the robot file's ``[settings]``, overridden by the joint's own
    ``joints[i].settings`` (register key -> Setting). ConfigError naming the file and key for a
    bad one. What the robot file implies besides ([bus] baud, [gains]) is the caller's to add.
    """
    base = parse_settings(
        servo_file,
        "settings",
        read_toml(servo_file).get("settings", {}) if servo_file.is_file() else {},
        table,
    )
    robot_data = read_toml(robot_file)
    overrides = parse_settings(robot_file, "settings", robot_data.get("settings", {}), table)
    raw_joints = robot_data.get("joints", [])
    out = []
    for index in range(joint_count):
        item = raw_joints[index] if index < len(raw_joints) else {}
        item = item if isinstance(item, dict) else {}
        own = parse_settings(
            robot_file, f"joints[{index}].settings", item.get("settings", {}), table
        )
        out.append({**base, **overrides, **own})
    return out
