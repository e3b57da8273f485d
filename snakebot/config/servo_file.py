"""Servo files, ``servos/<model>.toml``: the model, its physics, default gains and settings.

Every key is checked: ranges from snakebot.config.bounds, the model against its control table
(snakebot.servo_tables: the model number and the encoder resolution must agree with it), the
``[settings]`` against the table's registers, and no key may be unknown.
"""

from __future__ import annotations

import re
from pathlib import Path

from snakebot.backends.base import ServoGains
from snakebot.config import bounds
from snakebot.config.fields import Table, read_toml
from snakebot.config.schema import ServoModel, ServoPhysics
from snakebot.config.servo_settings import parse_settings
from snakebot.errors import ConfigError
from snakebot.servo_tables import ServoTable, UnknownModelError, supported_models, table_for_model

_MODEL_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]*")


def servo_file_name(model: str) -> str:
    """File stem of a servo model: ``XL430-W250`` -> ``xl430-w250``."""
    return model.strip().lower().replace("_", "-")


def find_servo_file(model: str, folders: list[Path], robot_path: Path) -> Path:
    """``servos/<model>.toml`` in the first of ``folders`` that has it; ConfigError naming the
    robot file's ``servo`` key if the name is not a model name or no folder has the file."""
    if not _MODEL_NAME.fullmatch(model.strip()):
        raise ConfigError(
            robot_path, "servo", f"expected a servo model name like XL430-W250, got {model!r}"
        )
    stem = servo_file_name(model)
    for folder in folders:
        path = folder / "servos" / f"{stem}.toml"
        if path.is_file():
            return path
    raise ConfigError(robot_path, "servo", f"no servo file servos/{stem}.toml for model {model!r}")


def servo_table(model: str, path: Path) -> ServoTable:
    """The control table of ``model``; ConfigError naming ``path`` and ``model`` if none."""
    try:
        return table_for_model(model)
    except UnknownModelError:
        raise ConfigError(
            path, "model", f"no control table for servo model {model!r}; snakebot supports "
            f"{', '.join(supported_models())}"
        ) from None


def parse_gains(table: Table) -> ServoGains:
    """A ``[gains]`` or ``[default_gains]`` table: Position P/I/D Gain register values."""
    gains = ServoGains(
        position_p=table.integer("position_p", within=bounds.GAIN),
        position_i=table.integer("position_i", 0, within=bounds.GAIN),
        position_d=table.integer("position_d", 0, within=bounds.GAIN),
    )
    table.done()
    return gains


def parse_servo_file(path: Path) -> ServoModel:
    """Read and validate one servo file; ConfigError naming the file and key of any problem."""
    root = Table(path, read_toml(path))
    name = root.text("model")
    table = servo_table(name, path)
    if servo_file_name(name) != path.stem:
        raise root.error(
            "model", f"this file is servos/{path.stem}.toml but names model {name!r}"
        )
    limits = bounds.SERVO
    model_number = root.integer("model_number", within=limits["model_number"])
    if model_number != table.model_number:
        raise root.error(
            "model_number",
            f"{table.model} is model number {table.model_number}, got {model_number}",
        )
    phys = root.table("physics")

    def number(key: str) -> float:
        return phys.number(key, within=limits[f"physics.{key}"])

    physics = ServoPhysics(
        stall_torque_nm=number("stall_torque_nm"),
        no_load_speed_rad_s=number("no_load_speed_rad_s"),
        nominal_voltage_v=number("nominal_voltage_v"),
        supply_voltage_v=number("supply_voltage_v"),
        armature_kgm2=number("armature_kgm2"),
        friction_loss_nm=number("friction_loss_nm"),
        viscous_damping_nms=number("viscous_damping_nms"),
        ticks_per_rev=phys.integer("ticks_per_rev", within=limits["physics.ticks_per_rev"]),
        pwm_limit=phys.integer("pwm_limit", within=limits["physics.pwm_limit"]),
        d_gain_loop_period_s=number("d_gain_loop_period_s"),
    )
    if physics.ticks_per_rev != table.specs.resolution:
        raise phys.error(
            "ticks_per_rev",
            f"{table.model} turns once in {table.specs.resolution} ticks, got "
            f"{physics.ticks_per_rev}",
        )
    pwm_max = table["pwm_limit"].maximum
    if physics.pwm_limit > pwm_max:
        raise phys.error("pwm_limit", f"{table.model}'s PWM Limit is at most {pwm_max}")
    phys.done()
    gains = parse_gains(root.table("default_gains"))
    parse_settings(path, "settings", root.data.get("settings", {}), table)
    root.mark_read("settings")
    root.done()
    return ServoModel(name, model_number, physics, gains, path)
