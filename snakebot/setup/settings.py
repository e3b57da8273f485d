"""The servo settings a robot wants: its servo file's ``[settings]``, robot and joint overrides.

Precedence, lowest first: ``servos/<model>.toml [settings]``, the robot file's ``[settings]``, a
joint's ``settings = {...}``. ID and Baud Rate come from the robot file (``[[joints]] servo_id``,
``[bus] baud``), Position P/I/D Gain from its ``[gains]``; the settings may not set them. The
wanted values are checked with the Dynamixel backend's own connect checks, so whatever
``snakebot config apply`` writes, ``snakebot run --backend dynamixel`` accepts.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from snakebot.backends.chain.checks import (
    LIMIT_KEYS,
    SETTINGS_KEYS,
    check_settings,
    current_position_mode,
    shutdown_name,
)
from snakebot.backends.chain.ticks import TickConverter
from snakebot.config.schema import JointConfig, RobotConfig
from snakebot.config.servos.settings import GAIN_KEYS, Setting, joint_settings
from snakebot.errors import ConfigError
from snakebot.families import family_for
from snakebot.servo_tables import ServoTable, table_for_model

__all__ = ["REBOOT_KEYS", "ChainSettings", "ServoSettings", "Setting", "load_settings"]

REQUIRED = (*SETTINGS_KEYS, *LIMIT_KEYS)
REBOOT_KEYS = frozenset({"startup_configuration"})
"""Settings that take effect at boot (e-Manual Startup Configuration): apply reboots after them."""


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


def _derived(robot: RobotConfig, table: ServoTable, source: Path) -> dict[str, Setting]:
    from snakebot.setup.bauds import baud_value  # setup imports settings, not the reverse

    try:
        baud_index = baud_value(table, robot.bus.baud)
    except ValueError as exc:
        raise ConfigError(source, "bus.baud", str(exc)) from None
    out = {"baud_rate": Setting(table["baud_rate"], baud_index, None, "[bus] baud", table)}
    for key, value in robot.gain_writes.items():
        out[key] = Setting(table[key], value, None, f"[gains] {GAIN_KEYS[key]}", table)
    return out


def load_settings(robot: RobotConfig) -> ChainSettings:
    """The settings ``robot`` wants on each servo; ConfigError naming file and key if invalid."""
    table = table_for_model(robot.servo.name)
    servo_file = robot.servo.source
    derived = _derived(robot, table, robot.source)
    given = joint_settings(servo_file, robot.source, robot.joint_count, table)
    servos = []
    for index, (joint, own) in enumerate(zip(robot.joints, given, strict=True)):
        merged = {**own, **derived}
        ordered = tuple(sorted(merged.values(), key=lambda s: s.register.address))
        servos.append(ServoSettings(index, joint.servo_id, ordered))
    chain = ChainSettings(robot, table, robot.bus.baud, tuple(servos))
    return _checked(chain, servo_file, robot.joints)


def has_watchdog(chain: ChainSettings) -> bool:
    """Whether the chain's servos have a Bus Watchdog on its bus's protocol."""
    family = family_for(chain.table, chain.robot.bus.protocol)
    return family.capabilities(chain.table).bus_watchdog


def _checked(
    chain: ChainSettings, servo_file: Path, joints: tuple[JointConfig, ...]
) -> ChainSettings:
    values: dict[int, dict[str, int]] = {}
    watchdog = has_watchdog(chain)
    # Without a Bus Watchdog, Alarm Shutdown is what cuts torque after the host died.
    required = REQUIRED if watchdog else (*REQUIRED, "shutdown")
    for servo in chain.servos:
        keys = {s.key: s.raw for s in servo.settings}
        missing = [k for k in required if k not in keys and k in chain.table]
        if missing:
            raise ConfigError(
                servo_file,
                "settings",
                f"missing {', '.join(missing)}: `snakebot "
                "run --backend dynamixel` checks them at connect, so set them here",
            )
        values[servo.servo_id] = keys
    family = family_for(chain.table, chain.robot.bus.protocol)
    if family.calibrates_homing_offset and any(
        s.key == "homing_offset" for servo in chain.servos for s in servo.settings
    ):
        raise ConfigError(
            servo_file,
            "settings.homing_offset",
            f"{family.label} servos hold their own zero: `snakebot calibrate` writes each "
            "one's Homing Offset, so the settings may not set it (remove the key)",
        )
    ids = [j.servo_id for j in joints]
    errors, notes = check_settings(
        values,
        ids,
        TickConverter.for_robot(chain.robot),
        watchdog=watchdog,
        position_mode=chain.table.specs.position_mode,
        current_position_mode=current_position_mode(chain.table),
        shutdown_register=shutdown_name(chain.table),
    )
    if errors:
        raise ConfigError(
            chain.robot.source,
            "settings",
            "`snakebot run` on this chain would refuse these settings: " + "; ".join(errors),
        )
    return ChainSettings(chain.robot, chain.table, chain.baud, chain.servos, tuple(notes))
