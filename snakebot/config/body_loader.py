"""Load mass-spring body files (``firmware_configs/bodies/<name>.toml``) into BodyConfig.

Validated like the robot files: unknown keys are rejected, ranges checked, and every error names
the file and the dotted key. ``load_robot_or_body`` is the one lookup behind ``--robot NAME``:
robots first, then bodies.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from snakebot.config.body import (
    CHANNEL_AXES,
    MILLER_TABLE,
    BodyConfig,
    BodySafety,
    ChannelAxis,
    GroundConfig,
    LatticeConfig,
    MuscleConfig,
    SpringConfig,
)
from snakebot.config.bounds import BODY
from snakebot.config.fields import Table, read_toml
from snakebot.config.loader import config_search_path, load_robot, resolve_robot_path, robot_names
from snakebot.config.schema import RobotConfig
from snakebot.errors import ConfigError

BODY_KIND = "mass-spring"
MAX_SEGMENTS = int(BODY["lattice.segments"].high)
# A point touches about nine springs; explicit spring forces need h * sqrt(9 k / m) well below 2.
_STABLE_STEP = 1.0


def body_names() -> list[str]:
    """Names of the bodies found on the search path (``bodies/*.toml``)."""
    names: set[str] = set()
    for folder in config_search_path():
        names.update(p.stem for p in (folder / "bodies").glob("*.toml"))
    return sorted(names)


def resolve_body_path(name_or_path: str | Path) -> Path:
    """A body file from a path, or a name looked up in ``bodies/`` on the search path."""
    candidate = Path(name_or_path)
    if candidate.suffix == ".toml" or candidate.exists():
        if not os.path.lexists(candidate):  # anything else there is refused when read
            raise ConfigError(candidate, "", "body file not found")
        return candidate
    for folder in config_search_path():
        path = folder / "bodies" / f"{name_or_path}.toml"
        if os.path.lexists(path):
            return path
    known = ", ".join(body_names()) or "none found"
    raise ConfigError(
        str(name_or_path), "", f"no body of that name (known bodies: {known}); pass a .toml path"
    )


def load_robot_or_body(name_or_path: str | Path) -> RobotConfig | BodyConfig:
    """What ``--robot`` names: a robot (servo chain) or a mass-spring body.

    A path is a body when its file says ``kind = "mass-spring"``; a name is looked up among the
    robots first, then the bodies. Raises ConfigError naming both lists when nothing matches.
    """
    candidate = Path(name_or_path)
    if candidate.suffix == ".toml" or candidate.exists():
        path = resolve_robot_path(candidate)
        return load_body(path) if "kind" in read_toml(path) else load_robot(path)
    name = str(name_or_path)
    if name in robot_names():
        return load_robot(name)
    if name in body_names():
        return load_body(name)
    robots = ", ".join(robot_names()) or "none found"
    bodies = ", ".join(body_names()) or "none found"
    raise ConfigError(
        name,
        "",
        f"no robot or body of that name (known robots: {robots}; known bodies: {bodies}); "
        "pass a .toml path",
    )


def load_body(name_or_path: str | Path) -> BodyConfig:
    """Load and validate a body by name (``worm``) or path; errors name file and key path."""
    path = resolve_body_path(name_or_path)
    root = Table(path, read_toml(path))
    kind = root.text("kind", choices=(BODY_KIND,))
    assert kind == BODY_KIND
    name = root.name("name", path.stem)
    lattice = _lattice(root.table("lattice"))
    springs = _springs(root.table("springs"))
    muscles = _muscles(root.table("muscles", required=False))
    ground_t = root.table("ground", required=False)
    ground = GroundConfig(
        friction=_number(ground_t, "friction", 0.3),
        directional=_boolean(ground_t, "directional", True),
    )
    ground_t.done()
    safety_t = root.table("safety", required=False)
    safety = BodySafety(
        ramp_s=_number(safety_t, "ramp_s", 1.0),
        stop_policy=safety_t.text("stop_policy", "hold", choices=("hold", "limp")),  # type: ignore[arg-type]
    )
    safety_t.done()
    twin_t = root.table("twin", required=False)
    timestep = _number(twin_t, "timestep_s", 0.001)
    body = BodyConfig(name, path, lattice, springs, muscles, ground, safety, timestep)
    stiffness = body.stiffness_n_per_m
    longest = _STABLE_STEP / math.sqrt(9.0 * stiffness / lattice.point_mass_kg)
    if timestep > longest:
        raise twin_t.error(
            "timestep_s",
            f"{timestep} s is too long for springs of {stiffness:.4g} N/m on "
            f"{lattice.point_mass_kg} kg points: need timestep_s < {longest:.3g} s",
        )
    twin_t.done()
    root.done()
    return body


def _lattice(table: Table) -> LatticeConfig:
    lattice = LatticeConfig(
        segments=table.integer("segments", within=BODY["lattice.segments"]),
        segment_length_m=_number(table, "segment_length_m"),
        width_m=_number(table, "width_m"),
        height_m=_number(table, "height_m"),
        point_mass_kg=_number(table, "point_mass_kg"),
        point_radius_m=_number(table, "point_radius_m"),
    )
    smallest = min(lattice.segment_length_m, lattice.width_m, lattice.height_m)
    if 2 * lattice.point_radius_m >= smallest:
        raise table.error(
            "point_radius_m",
            f"points of radius {lattice.point_radius_m} m overlap on a cube side of {smallest} m "
            "(need 2 * point_radius_m < the shortest side)",
        )
    table.done()
    return lattice


def _springs(table: Table) -> SpringConfig:
    time_unit = _number(table, "time_unit_s", 0.005)
    if table.has("preset"):
        preset = table.text("preset", choices=tuple(MILLER_TABLE))
        for key in ("k", "damping"):
            if table.has(key):
                raise table.error(
                    key, f"give either preset = {preset!r} or k and damping, not both"
                )
        k, damping = MILLER_TABLE[preset]
        springs = SpringConfig(k, damping, time_unit, preset)
    else:
        if not table.has("k"):
            raise table.error(
                "preset",
                f"missing: give preset (one of {', '.join(MILLER_TABLE)}) or k and damping",
            )
        springs = SpringConfig(
            _number(table, "k"),
            _number(table, "damping"),
            time_unit,
        )
    table.done()
    return springs


def _muscles(table: Table) -> MuscleConfig:
    channels = _channels(table)
    muscles = MuscleConfig(
        channels=channels,
        max_bend_rad=_number(table, "max_bend_rad", 0.6),
        max_contraction=_number(table, "max_contraction", 0.4),
        max_rate_per_s=_number(table, "max_rate_per_s", 20.0),
        volume_preservation=_boolean(table, "volume_preservation", False),
    )
    table.done()
    return muscles


def _number(table: Table, key: str, default: float | None = None) -> float:
    """A number of a body table within its range in snakebot.config.bounds.BODY."""
    return table.number(key, default, within=BODY[f"{table.path}.{key}"])


def _channels(table: Table) -> tuple[ChannelAxis, ...]:
    key = "channels"
    table._seen.add(key)
    value = table.data.get(key, list(CHANNEL_AXES))
    expected = f"a list of distinct channels from {list(CHANNEL_AXES)}"
    if not isinstance(value, list) or not value:
        raise table.error(key, f"expected {expected}, got {value!r}")
    for item in value:
        if item not in CHANNEL_AXES:
            raise table.error(key, f"unknown channel {item!r}; expected {expected}")
    if len(set(value)) != len(value):
        raise table.error(key, f"channels repeat in {value!r}; expected {expected}")
    return tuple(value)


def _boolean(table: Table, key: str, default: bool) -> bool:
    table._seen.add(key)
    value = table.data.get(key, default)
    if not isinstance(value, bool):
        raise table.error(key, f"expected true or false, got {value!r}")
    return value
