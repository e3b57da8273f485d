"""Servo files, ``servos/<model>.toml``: the model, its physics, the twin's optional servo-model
parts (``[twin]``) and settings.

Every key is checked: ranges from snakebot.config.bounds, the model against its control table
(snakebot.servo_tables: the model number and the encoder resolution must agree with it), the
``[settings]`` against the table's registers, and no key may be unknown.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path

from snakebot.config import bounds
from snakebot.config.fields import Table, read_toml
from snakebot.config.schema import (
    COMPLIANCE_GAIN_KEYS,
    PID_GAIN_KEYS,
    GainRegisters,
    ServoModel,
    ServoPhysics,
)
from snakebot.config.servos.settings import Setting, parse_settings
from snakebot.config.servos.twin import read_servo_extras
from snakebot.errors import ConfigError
from snakebot.servo_tables import ServoTable, UnknownModelError, supported_models, table_for_model
from snakebot.types import PDGains

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
        if os.path.lexists(path):  # a directory or FIFO there is refused when read, not skipped
            return path
    raise ConfigError(robot_path, "servo", f"no servo file servos/{stem}.toml for model {model!r}")


def servo_table(model: str, path: Path) -> ServoTable:
    """The control table of ``model``; ConfigError naming ``path`` and ``model`` if none."""
    try:
        return table_for_model(model)
    except UnknownModelError:
        raise ConfigError(
            path,
            "model",
            f"no control table for servo model {model!r}; snakebot supports "
            f"{', '.join(supported_models())}",
        ) from None


def _register_bounds(servo: ServoModel, gain: str, maximum: int) -> bounds.Bounds:
    return bounds.Bounds(0, maximum, "", f"{servo.name}'s Position {gain} Gain register range")


_PID_KEYS: tuple[str, ...] = ("position_p", "position_i", "position_d", "kd_nms_per_rad")
_COMPLIANCE_KEYS: tuple[str, ...] = ("compliance_slope",)


def _refuse_other_loop(table: Table, servo: ServoModel) -> None:
    """ConfigError naming a [gains] key of the other kind of position loop."""
    if servo.gain_kind == "pid":
        wrong, have = _COMPLIANCE_KEYS, "Position P/I/D Gain (position_p, position_i, position_d)"
        why = "is an AX-series Compliance Slope setting"
    else:
        wrong, have = _PID_KEYS, "a Compliance Slope (compliance_slope, or kp_nm_per_rad)"
        why = "is a Position P/I/D Gain setting"
    for key in wrong:
        if table.has(key):
            detail = (
                " (the damping has no register; it comes from the twin's joint damping)"
                if key == "kd_nms_per_rad"
                else ""
            )
            raise table.error(key, f"{key} {why}; {servo.name} has {have} instead{detail}")


def _parse_compliance(table: Table, servo: ServoModel, control: ServoTable) -> PDGains:
    if table.has("compliance_slope") and table.has("kp_nm_per_rad"):
        raise table.error(
            "kp_nm_per_rad",
            "give the stiffness either as compliance_slope or in SI (kp_nm_per_rad), not both",
        )
    if table.has("kp_nm_per_rad"):
        reach = servo.max_gains.kp_nm_per_rad
        return PDGains(
            table.number(
                "kp_nm_per_rad",
                within=bounds.Bounds(
                    0,
                    reach,
                    "N·m/rad",
                    f"what {servo.name}'s smallest Compliance Slope reaches at the "
                    "supply voltage and Torque Limit",
                ),
            ),
            0.0,
        )
    register = control["cw_compliance_slope"]
    slope = table.integer(
        "compliance_slope",
        servo.default_slope,
        within=bounds.Bounds(
            max(register.minimum, 1),
            register.maximum,
            "",
            f"{servo.name}'s Compliance Slope register range (levels 2, 4, ..., 128)",
        ),
    )
    return servo.gains_from(dict.fromkeys(COMPLIANCE_GAIN_KEYS, slope))


def parse_gains(table: Table, servo: ServoModel) -> tuple[PDGains, int]:
    """A robot file's ``[gains]``: (SI gains, Position I Gain register).

    For a "pid" servo the gains are the Position P/D Gain registers (``position_p``,
    ``position_d``), converted with the servo's mapping, or SI values (``kp_nm_per_rad``,
    ``kd_nms_per_rad``) up to what the registers reach; ``position_i`` (Dynamixel only) goes
    with either. For a "compliance" servo (AX) the stiffness is ``compliance_slope`` (the CW/CCW
    Compliance Slope register, both directions) or ``kp_nm_per_rad``; its I register is 0.
    ConfigError naming the key if both forms are given, a key belongs to the other kind of
    loop, a value is out of range, or a key is unknown.
    """
    _refuse_other_loop(table, servo)
    if servo.gain_kind == "compliance":
        gains = _parse_compliance(table, servo, servo_table(servo.name, servo.source))
        table.done()
        return gains, 0
    maxima = servo.gain_max
    si = [k for k in ("kp_nm_per_rad", "kd_nms_per_rad") if table.has(k)]
    registers = [k for k in ("position_p", "position_d") if table.has(k)]
    if si and registers:
        raise table.error(
            si[0],
            f"give the gains either as registers ({', '.join(registers)}) or in SI "
            "(kp_nm_per_rad, kd_nms_per_rad), not both",
        )
    position_i = table.integer(
        "position_i", 0, within=_register_bounds(servo, "I", maxima.position_i)
    )
    if si:
        reach = servo.gain_mapping.max_gains
        why = f"what {servo.name}'s Position {{}} Gain reaches at the supply voltage"
        gains = PDGains(
            table.number(
                "kp_nm_per_rad",
                within=bounds.Bounds(0, reach.kp_nm_per_rad, "N·m/rad", why.format("P")),
            ),
            table.number(
                "kd_nms_per_rad",
                0.0,
                within=bounds.Bounds(0, reach.kd_nms_per_rad, "N·m·s/rad", why.format("D")),
            ),
        )
    else:
        p = table.integer("position_p", within=_register_bounds(servo, "P", maxima.position_p))
        d = table.integer("position_d", 0, within=_register_bounds(servo, "D", maxima.position_d))
        gains = servo.gains_of(GainRegisters(p, position_i, d))
    table.done()
    return gains, position_i


# Keys older servo files had whose values now come, once, from the control-table data.
_TABLE_FACTS = {
    "model_number": "the model number",
    "physics.stall_torque_nm": "the stall torque",
    "physics.no_load_speed_rad_s": "the no-load speed",
    "physics.nominal_voltage_v": "the voltage of the datasheet's torque and speed",
    "physics.ticks_per_rev": "the encoder resolution (the model data's [model.ticks])",
    "default_gains": "the factory Position P/I/D Gain",
}

# A compliance model has no P/D registers, so the gain mapping's keys mean nothing for it.
_PID_PHYSICS = ("pwm_limit", "d_gain_loop_period_s", "p_gain_divisor", "d_gain_divisor")


def _refuse_table_facts(root: Table, table: ServoTable) -> None:
    for key, what in _TABLE_FACTS.items():
        section, _, name = key.rpartition(".")
        holder = root.data.get(section) if section else root.data
        if isinstance(holder, dict) and name in holder:
            raise ConfigError(
                root.source,
                key,
                f"{what} of {table.model} is kept once, in snakebot's "
                "control-table data (snakebot/servo_tables/data); remove this key"
                + (
                    "; a robot's gains go in its robot file's [gains]"
                    if key == "default_gains"
                    else ""
                ),
            )


def default_gains(table: ServoTable) -> GainRegisters:
    """The factory Position P/I/D Gain register values of a model (its control table; all 0
    on a compliance model, which has none; I 0 on a P/D model such as the SCS0009)."""
    if table.specs.gains != "pid":
        return GainRegisters(0, 0, 0)
    return GainRegisters(*(table[key].default if key in table else 0 for key in PID_GAIN_KEYS))


def gain_maxima(table: ServoTable) -> GainRegisters:
    """The largest Position P/I/D Gain register values a model takes (its control table; all
    0 on a compliance model)."""
    if table.specs.gains != "pid":
        return GainRegisters(0, 0, 0)
    return GainRegisters(*(table[key].maximum if key in table else 0 for key in PID_GAIN_KEYS))


def output_full_scale(table: ServoTable) -> tuple[str, int]:
    """(register key, maximum) of the register that sets the output's full scale: PWM Limit on
    Protocol 2.0 tables, Max Torque (1023 = 100 %) on the Protocol 1.0 AX/MX tables."""
    key = "pwm_limit" if "pwm_limit" in table else "max_torque"
    return key, table[key].maximum


def torque_limit_fraction(settings: Mapping[str, Setting], table: ServoTable) -> float:
    """The Torque Limit a compliance model runs at, as a fraction of full torque: the
    ``torque_limit`` setting, else ``max_torque`` (Torque Limit takes Max Torque's value at
    power-on, e-Manual ax-12a.md), else Max Torque's factory value."""
    register = table["max_torque"]
    for key in ("torque_limit", "max_torque"):
        if key in settings:
            return settings[key].raw / register.maximum
    return register.default / register.maximum


def parse_servo_file(path: Path) -> ServoModel:
    """Read and validate one servo file; ConfigError naming the file and key of any problem.

    The datasheet facts (model number, stall torque, no-load speed and its voltage, resolution,
    factory gains, register ranges) come from the model's control table; the file adds the
    supply voltage, the twin's estimates, the gain mapping's divisors and the twin's optional
    servo-model parts (``[twin]``, snakebot.config.servos.twin).
    """
    root = Table(path, read_toml(path))
    name = root.text("model")
    table = servo_table(name, path)
    if servo_file_name(name) != path.stem:
        raise root.error("model", f"this file is servos/{path.stem}.toml but names model {name!r}")
    _refuse_table_facts(root, table)
    limits = bounds.SERVO
    phys = root.table("physics")

    def number(key: str) -> float:
        return phys.number(key, within=limits[f"physics.{key}"])

    specs = table.specs
    compliance = specs.gains == "compliance"
    if compliance:
        for key in _PID_PHYSICS:
            if phys.has(key):
                raise phys.error(
                    key,
                    f"{table.model} has no Position P/D Gain (its loop is "
                    "Compliance Slope, snakebot.servo.ComplianceMapping); remove it",
                )
    full_key, full_max = output_full_scale(table)
    physics = ServoPhysics(
        stall_torque_nm=specs.stall_torque_nm,
        no_load_speed_rad_s=specs.no_load_speed_rad_s,
        nominal_voltage_v=specs.nominal_voltage_v,
        supply_voltage_v=number("supply_voltage_v"),
        armature_kgm2=number("armature_kgm2"),
        friction_loss_nm=number("friction_loss_nm"),
        viscous_damping_nms=number("viscous_damping_nms"),
        ticks=specs.ticks,
        # On a compliance model the P/D mapping is unused: the full scale and unit divisors.
        pwm_limit=full_max
        if compliance
        else phys.integer("pwm_limit", within=limits["physics.pwm_limit"]),
        d_gain_loop_period_s=1e-3 if compliance else number("d_gain_loop_period_s"),
        p_gain_divisor=1.0 if compliance else number("p_gain_divisor"),
        d_gain_divisor=1.0 if compliance else number("d_gain_divisor"),
    )
    if physics.pwm_limit > full_max:
        name = table[full_key].name
        raise phys.error("pwm_limit", f"{table.model}'s {name} is at most {full_max}")
    phys.done()
    twin = root.table("twin", required=False)
    if twin.has("p_gain_divisor"):
        raise twin.error(
            "p_gain_divisor",
            "the P-gain divisor is physics.p_gain_divisor (one key for the twin "
            "and the bus); a robot's [twin.servo] may override it",
        )
    physics = replace(physics, extras=read_servo_extras(twin, physics.extras))
    twin.done()
    settings = parse_settings(path, "settings", root.data.get("settings", {}), table)
    root.mark_read("settings")
    root.done()
    model = ServoModel(
        name, table.model_number, physics, default_gains(table), gain_maxima(table), path
    )
    if not compliance:
        return model
    return replace(
        model,
        gain_kind="compliance",
        default_slope=table["cw_compliance_slope"].default,
        torque_limit=torque_limit_fraction(settings, table),
    )
