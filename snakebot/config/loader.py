"""Load robot and servo files from ``firmware_configs/`` into validated dataclasses."""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path
from typing import Any

from snakebot.config import bounds, paths
from snakebot.config.fields import Table, read_toml
from snakebot.config.ports import check_port
from snakebot.config.schema import (
    BusConfig,
    JointConfig,
    LinkConfig,
    RobotConfig,
    SafetyConfig,
    ServoModel,
    TwinConfig,
)
from snakebot.config.servos.file import (
    find_servo_file,
    parse_gains,
    parse_servo_file,
    servo_file_name,
    servo_table,
    torque_limit_fraction,
)
from snakebot.config.servos.settings import parse_settings
from snakebot.config.servos.twin import read_servo_extras
from snakebot.errors import ConfigError
from snakebot.families import family_for
from snakebot.servo_tables import ServoTable

__all__ = ["load_robot", "load_servo_model", "robot_names", "servo_file_name"]


def config_search_path() -> list[Path]:
    """Folders searched for ``robots/<name>.toml``, first match wins.

    ``$SNAKEBOT_CONFIG_PATH`` (os.pathsep-separated), ``./firmware_configs``, the user's config
    directory, then the robots shipped with snakebot (snakebot.config.paths says where).
    """
    return [folder.path for folder in paths.config_search_path()]


def robot_names() -> list[str]:
    """Names (file stems, sorted, each once) of the robots in ``robots/`` of every folder on the
    search path; a name in two folders resolves to the first (``snakebot robots`` shows both)."""
    names: set[str] = set()
    for folder in config_search_path():
        names.update(p.stem for p in (folder / "robots").glob("*.toml"))
    return sorted(names)


def resolve_robot_path(name_or_path: str | Path) -> Path:
    """A robot file from a path (``.toml`` or an existing path), or a name looked up on the
    search path, first match wins. ConfigError naming the path ("robot file not found") or the
    name (listing the known robots) when there is none."""
    candidate = Path(name_or_path)
    if candidate.suffix == ".toml" or candidate.exists():
        if not os.path.lexists(candidate):  # anything else there is refused when read
            raise ConfigError(candidate, "", "robot file not found")
        return candidate
    for folder in config_search_path():
        path = folder / "robots" / f"{name_or_path}.toml"
        if os.path.lexists(path):
            return path
    known = ", ".join(robot_names()) or "none found"
    raise ConfigError(
        str(name_or_path), "", f"no robot of that name (known robots: {known}); pass a .toml path"
    )


def load_servo_model(model: str, robot_path: Path) -> ServoModel:
    """Read ``servos/<model>.toml`` beside the robot's folder, else the first on the search
    path; ConfigError naming ``robot_path`` and its ``servo`` key if there is none, or naming the
    servo file and key of its first invalid value."""
    folders = [robot_path.resolve().parent.parent, *config_search_path()]
    return parse_servo_file(find_servo_file(model, folders, robot_path))


def _with_servo_fit(servo: ServoModel, table: Table) -> ServoModel:
    """``[twin.servo]``: servo parameters fitted by ``snakebot sysid``; the twin uses them.

    ``p_gain_divisor`` overrides the servo file's, so it changes the servo's gain mapping: the
    robot's register gains mean other SI gains, on the twin and on the bus alike.
    """
    physics = servo.physics

    def number(key: str, default: float | None) -> float:
        return table.number(key, default, within=bounds.ROBOT[f"twin.servo.{key}"])

    fitted = replace(
        physics,
        stiffness_scale=number("stiffness_scale", 1.0),
        damping_nms=number("damping_nms", None) if table.has("damping_nms") else None,
        armature_kgm2=number("armature_kgm2", physics.armature_kgm2),
        friction_loss_nm=number("friction_loss_nm", physics.friction_loss_nm),
        actuator_delay_s=(
            number("actuator_delay_s", None) if table.has("actuator_delay_s") else None
        ),
        p_gain_divisor=number("p_gain_divisor", physics.p_gain_divisor),
        extras=read_servo_extras(table, physics.extras),
    )
    table.done()
    return replace(servo, physics=fitted)


def load_robot(name_or_path: str | Path) -> RobotConfig:
    """Load and validate a robot by name (``snake8``) or path.

    Every key of the robot file and of its servo file is checked (ranges in
    snakebot.config.bounds, settings against the servo's control table); ConfigError names the
    file and the key path of the first problem, including a key that is not known.
    """
    path = resolve_robot_path(name_or_path)
    root = Table(path, read_toml(path))
    limits = bounds.ROBOT

    def number(table: Table, key: str, default: float | None = None) -> float:
        return table.number(key, default, within=limits[f"{table.path}.{key}"])

    name = root.name("name", path.stem)
    servo = load_servo_model(root.text("servo"), path)
    control_table = servo_table(servo.name, servo.source)

    bus_t = root.table("bus")
    bus = BusConfig(
        port=check_port(
            bus_t.text("port", "/dev/ttyUSB0"), source=path, key="bus.port", allow_emulator=False
        ),
        baud=bus_t.integer(
            "baud", 1_000_000, choices=sorted(set(control_table.baud_rates.values()))
        ),
        protocol=bus_t.number("protocol", control_table.protocol),
    )
    try:  # the model's protocols: Dynamixel 1.0/2.0, Feetech STS 0.0 (SDK protocol_end)
        family_for(control_table, bus.protocol)
    except ConfigError as exc:
        raise bus_t.error("protocol", exc.reason) from exc
    bus_t.done()

    link_t = root.table("link")
    link = LinkConfig(
        length_m=number(link_t, "length_m"),
        radius_m=number(link_t, "radius_m"),
        mass_kg=number(link_t, "mass_kg"),
    )
    if 2 * link.radius_m >= link.length_m:
        raise link_t.error(
            "radius_m",
            f"a capsule of radius {link.radius_m} m does not fit a {link.length_m} m "
            "module (need 2*radius_m < length_m)",
        )
    link_t.done()

    joints = _parse_joints(root, control_table)

    twin_t = root.table("twin", required=False)
    twin = TwinConfig(
        timestep_s=number(twin_t, "timestep_s", 0.002),
        ground=twin_t.text("ground", "isotropic", choices=("anisotropic", "isotropic")),  # type: ignore[arg-type]
        axial_friction=number(twin_t, "axial_friction", 1.0),
        lateral_friction=number(twin_t, "lateral_friction", 1.0),
        friction_model=twin_t.text("friction_model", "auto", choices=("auto", "pairs", "scale")),  # type: ignore[arg-type]
        backward_friction=(
            number(twin_t, "backward_friction") if twin_t.has("backward_friction") else None
        ),
    )
    # Before [gains]: a fitted p_gain_divisor changes what the gain registers mean.
    servo = _with_servo_fit(servo, twin_t.table("servo", required=False))
    twin_t.done()

    # Servo settings for the whole chain; merged per servo and checked against the backend's
    # connect checks by snakebot.setup (config diff/apply, calibrate). Before [gains]: a
    # compliance servo's Torque Limit sets what its Compliance Slope means.
    settings = parse_settings(path, "settings", root.data.get("settings", {}), control_table)
    root.mark_read("settings")
    if servo.gain_kind == "compliance" and {"torque_limit", "max_torque"} & set(settings):
        base = parse_settings(
            servo.source, "settings", read_toml(servo.source).get("settings", {}), control_table
        )
        servo = replace(
            servo, torque_limit=torque_limit_fraction({**base, **settings}, control_table)
        )
    if root.has("gains"):
        gains, position_i = parse_gains(root.table("gains"), servo)
    else:
        gains, position_i = servo.factory_gains, servo.default_gains.position_i
    root.mark_read("gains")

    safety_t = root.table("safety", required=False)
    safety = SafetyConfig(
        ramp_s=number(safety_t, "ramp_s", 1.0),
        max_speed_fraction=number(safety_t, "max_speed_fraction", 0.9),
        stop_policy=safety_t.text("stop_policy", "hold", choices=("hold", "limp")),  # type: ignore[arg-type]
    )
    safety_t.done()
    root.done()
    return RobotConfig(name, path, servo, bus, joints, link, gains, safety, twin, position_i)


def _joint_fields(table: Table) -> dict[str, Any]:
    """The per-joint fields present in ``table`` (a joint, or ``[joint_defaults]``), checked."""
    fields: dict[str, Any] = {}
    for key in ("servo_id", "axis", "zero_offset_rad", "direction", "lower_rad", "upper_rad"):
        if not table.has(key):
            continue
        if key == "axis":
            fields[key] = table.text(key, choices=("yaw", "pitch"))
        elif key == "direction":
            fields[key] = table.integer(key, choices=(1, -1))
        elif key == "servo_id":
            fields[key] = table.integer(key, within=bounds.ROBOT["joints[].servo_id"])
        else:
            fields[key] = table.number(key, within=bounds.ROBOT[f"joints[].{key}"])
    return fields


def _parse_joints(root: Table, control_table: ServoTable) -> tuple[JointConfig, ...]:
    # Defaults are checked where they are written, so an error names joint_defaults.<key>.
    defaults_t = root.table("joint_defaults", required=False)
    defaults = _joint_fields(defaults_t)
    if "servo_id" in defaults:
        raise defaults_t.error("servo_id", "every joint has its own servo_id; set it per joint")
    defaults_t.done()
    joints = []
    seen_ids: dict[int, int] = {}
    items = root.tables("joints")
    fewest, most = bounds.JOINT_COUNT
    if not fewest <= len(items) <= most:
        raise root.error("joints", f"expected {fewest} to {most} joints, got {len(items)}")
    for index, item in enumerate(items):
        fields = {**defaults, **_joint_fields(item)}
        for key in ("servo_id", "axis", "lower_rad", "upper_rad"):
            if key not in fields:
                raise item.error(
                    key,
                    "missing (required; lower_rad, upper_rad and axis may come "
                    "from [joint_defaults])",
                )
        servo_id = fields["servo_id"]
        if servo_id in seen_ids:
            raise item.error(
                "servo_id", f"servo ID {servo_id} is already used by joints[{seen_ids[servo_id]}]"
            )
        seen_ids[servo_id] = index
        joint = JointConfig(
            servo_id=servo_id,
            axis=fields["axis"],
            zero_offset_rad=fields.get("zero_offset_rad", 0.0),
            direction=fields.get("direction", 1),
            lower_rad=fields["lower_rad"],
            upper_rad=fields["upper_rad"],
        )
        if joint.upper_rad - joint.lower_rad <= 0:
            raise item.error("upper_rad", "expected upper_rad > lower_rad")
        parse_settings(
            Path(root.source), f"{item.path}.settings", item.data.get("settings", {}), control_table
        )
        item.mark_read("settings")
        item.done()
        joints.append(joint)
    return tuple(joints)
