"""Load robot and servo files from ``firmware_configs/`` into validated dataclasses."""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

from snakebot.backends.base import ServoGains
from snakebot.config.fields import Table
from snakebot.config.ports import check_port
from snakebot.config.schema import (
    MAX_ACTUATOR_DELAY_S,
    BusConfig,
    JointConfig,
    LinkConfig,
    RobotConfig,
    SafetyConfig,
    ServoModel,
    ServoPhysics,
    TwinConfig,
)
from snakebot.errors import ConfigError

BAUD_RATES = (9600, 57600, 115200, 1_000_000, 2_000_000, 3_000_000, 4_000_000, 4_500_000)


def config_search_path() -> list[Path]:
    """Folders searched for ``robots/<name>.toml``, first match wins.

    ``$SNAKEBOT_CONFIG_PATH`` (os.pathsep-separated), then ``./firmware_configs``, then the
    ``firmware_configs/`` of the source tree snakebot was installed from.
    """
    paths = [Path(p) for p in os.environ.get("SNAKEBOT_CONFIG_PATH", "").split(os.pathsep) if p]
    paths.append(Path.cwd() / "firmware_configs")
    paths.append(Path(__file__).resolve().parents[2] / "firmware_configs")
    return paths


def robot_names() -> list[str]:
    """Names of the robots found on the search path."""
    names: set[str] = set()
    for folder in config_search_path():
        names.update(p.stem for p in (folder / "robots").glob("*.toml"))
    return sorted(names)


def resolve_robot_path(name_or_path: str | Path) -> Path:
    """A robot file from a path, or a name looked up on the search path."""
    candidate = Path(name_or_path)
    if candidate.suffix == ".toml" or candidate.exists():
        if not candidate.is_file():
            raise ConfigError(candidate, "", "robot file not found")
        return candidate
    for folder in config_search_path():
        path = folder / "robots" / f"{name_or_path}.toml"
        if path.is_file():
            return path
    known = ", ".join(robot_names()) or "none found"
    raise ConfigError(
        str(name_or_path), "", f"no robot of that name (known robots: {known}); pass a .toml path"
    )


def _read_toml(path: Path) -> dict[str, Any]:
    try:
        with path.open("rb") as handle:
            return tomllib.load(handle)
    except OSError as exc:
        raise ConfigError(path, "", f"cannot read: {exc.strerror}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(path, "", f"not valid TOML: {exc}") from exc


def servo_file_name(model: str) -> str:
    """File stem of a servo model: ``XL430-W250`` -> ``xl430-w250``."""
    return model.strip().lower().replace("_", "-")


def load_servo_model(model: str, robot_path: Path) -> ServoModel:
    """Read ``servos/<model>.toml`` beside the robot's folder (or on the search path)."""
    stem = servo_file_name(model)
    folders = [robot_path.resolve().parent.parent, *config_search_path()]
    for folder in folders:
        path = folder / "servos" / f"{stem}.toml"
        if path.is_file():
            return _parse_servo(path)
    raise ConfigError(robot_path, "servo", f"no servo file servos/{stem}.toml for model {model!r}")


def _parse_servo(path: Path) -> ServoModel:
    root = Table(path, _read_toml(path))
    name = root.text("model")
    model_number = root.integer("model_number", minimum=0)
    phys = root.table("physics")
    physics = ServoPhysics(
        stall_torque_nm=phys.number("stall_torque_nm", positive=True),
        no_load_speed_rad_s=phys.number("no_load_speed_rad_s", positive=True),
        nominal_voltage_v=phys.number("nominal_voltage_v", positive=True),
        supply_voltage_v=phys.number("supply_voltage_v", positive=True),
        armature_kgm2=phys.number("armature_kgm2", minimum=0.0),
        friction_loss_nm=phys.number("friction_loss_nm", minimum=0.0),
        viscous_damping_nms=phys.number("viscous_damping_nms", minimum=0.0),
        ticks_per_rev=phys.integer("ticks_per_rev", minimum=1),
        pwm_limit=phys.integer("pwm_limit", minimum=1),
        d_gain_loop_period_s=phys.number("d_gain_loop_period_s", positive=True),
    )
    phys.done()
    gains = _parse_gains(root.table("default_gains"))
    # Later sections (settings to flash) are read by the servo-setup tools, not here.
    root._seen.update(k for k in root.data if k not in root._seen)
    return ServoModel(name, model_number, physics, gains, path)


def _parse_gains(table: Table) -> ServoGains:
    gains = ServoGains(
        position_p=table.integer("position_p", minimum=0, maximum=16383),
        position_i=table.integer("position_i", 0, minimum=0, maximum=16383),
        position_d=table.integer("position_d", 0, minimum=0, maximum=16383),
    )
    table.done()
    return gains


def _with_servo_fit(servo: ServoModel, table: Table) -> ServoModel:
    """``[twin.servo]``: servo parameters fitted by ``snakebot sysid``; the twin uses them."""
    physics = servo.physics
    fitted = replace(
        physics,
        stiffness_scale=table.number("stiffness_scale", 1.0, positive=True),
        damping_nms=table.number("damping_nms", -1.0) if table.has("damping_nms") else None,
        armature_kgm2=table.number("armature_kgm2", physics.armature_kgm2, minimum=0.0),
        friction_loss_nm=table.number("friction_loss_nm", physics.friction_loss_nm, minimum=0.0),
        actuator_delay_s=(
            table.number("actuator_delay_s", minimum=0.0, maximum=MAX_ACTUATOR_DELAY_S)
            if table.has("actuator_delay_s")
            else None
        ),
    )
    if fitted.damping_nms is not None and fitted.damping_nms < 0:
        raise table.error("damping_nms", f"expected a number >= 0, got {fitted.damping_nms}")
    table.done()
    return replace(servo, physics=fitted)


def load_robot(name_or_path: str | Path) -> RobotConfig:
    """Load and validate a robot by name (``snake8``) or path; errors name file and key path."""
    path = resolve_robot_path(name_or_path)
    root = Table(path, _read_toml(path))
    name = root.text("name", path.stem)
    servo = load_servo_model(root.text("servo"), path)

    bus_t = root.table("bus")
    bus = BusConfig(
        port=check_port(
            bus_t.text("port", "/dev/ttyUSB0"), source=path, key="bus.port", allow_emulator=False
        ),
        baud=bus_t.integer("baud", 1_000_000, choices=BAUD_RATES),
        protocol=bus_t.number("protocol", 2.0),
    )
    if bus.protocol not in (1.0, 2.0):
        raise bus_t.error("protocol", f"expected 1.0 or 2.0, got {bus.protocol}")
    bus_t.done()

    link_t = root.table("link")
    link = LinkConfig(
        length_m=link_t.number("length_m", positive=True, maximum=1.0),
        radius_m=link_t.number("radius_m", positive=True),
        mass_kg=link_t.number("mass_kg", positive=True),
    )
    if 2 * link.radius_m >= link.length_m:
        raise link_t.error(
            "radius_m",
            f"a capsule of radius {link.radius_m} m does not fit a {link.length_m} m "
            "module (need 2*radius_m < length_m)",
        )
    link_t.done()

    joints = _parse_joints(root)
    gains = _parse_gains(root.table("gains")) if root.has("gains") else servo.default_gains
    if not root.has("gains"):
        root._seen.add("gains")

    safety_t = root.table("safety", required=False)
    safety = SafetyConfig(
        ramp_s=safety_t.number("ramp_s", 1.0, minimum=0.0),
        max_speed_fraction=safety_t.number("max_speed_fraction", 0.9, positive=True, maximum=1.0),
        stop_policy=safety_t.text("stop_policy", "hold", choices=("hold", "limp")),  # type: ignore[arg-type]
    )
    safety_t.done()

    twin_t = root.table("twin", required=False)
    twin = TwinConfig(
        timestep_s=twin_t.number("timestep_s", 0.002, positive=True, maximum=0.02),
        ground=twin_t.text("ground", "isotropic", choices=("anisotropic", "isotropic")),  # type: ignore[arg-type]
        axial_friction=twin_t.number("axial_friction", 1.0, minimum=0.0),
        lateral_friction=twin_t.number("lateral_friction", 1.0, minimum=0.0),
    )
    servo = _with_servo_fit(servo, twin_t.table("servo", required=False))
    twin_t.done()
    root._seen.add("settings")  # servo settings overrides, read by snakebot.setup
    root.done()
    return RobotConfig(name, path, servo, bus, joints, link, gains, safety, twin)


def _parse_joints(root: Table) -> tuple[JointConfig, ...]:
    defaults_t = root.table("joint_defaults", required=False)
    defaults = {key: defaults_t.data[key] for key in defaults_t.data}
    defaults_t._seen.update(defaults)
    allowed = {"axis", "zero_offset_rad", "direction", "lower_rad", "upper_rad"}
    for key in defaults:
        if key not in allowed:
            raise defaults_t.error(
                key, f"unknown key (known keys here: {', '.join(sorted(allowed))})"
            )
    joints = []
    seen_ids: dict[int, int] = {}
    items = root.tables("joints")
    if not 2 <= len(items) <= 64:
        raise root.error("joints", f"expected 2 to 64 joints, got {len(items)}")
    for index, item in enumerate(items):
        merged = Table(item.source, {**defaults, **item.data}, item.path)
        servo_id = merged.integer("servo_id", minimum=0, maximum=252)
        if servo_id in seen_ids:
            raise merged.error(
                "servo_id", f"servo ID {servo_id} is already used by joints[{seen_ids[servo_id]}]"
            )
        seen_ids[servo_id] = index
        joint = JointConfig(
            servo_id=servo_id,
            axis=merged.text("axis", choices=("yaw", "pitch")),  # type: ignore[arg-type]
            zero_offset_rad=merged.number(
                "zero_offset_rad", 0.0, minimum=-math.pi, maximum=math.pi
            ),
            direction=merged.integer("direction", 1, choices=(1, -1)),
            lower_rad=merged.number("lower_rad", minimum=-math.pi, maximum=0.0),
            upper_rad=merged.number("upper_rad", minimum=0.0, maximum=math.pi),
        )
        if joint.upper_rad - joint.lower_rad <= 0:
            raise merged.error("upper_rad", "expected upper_rad > lower_rad")
        merged._seen.add("settings")  # per-joint servo settings, read by snakebot.setup
        merged.done()
        joints.append(joint)
    return tuple(joints)
