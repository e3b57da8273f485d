"""``NAME[:key=value,...]`` parsed against the terrain registry (``snakebot.backends.terrains``):
the one ``parse_terrain``, for the rigid twin and the mass-spring bodies alike."""

from __future__ import annotations

from typing import Any

from snakebot.backends.terrains import get_terrain, terrain_names
from snakebot.backends.twin.terrain.base import Terrain
from snakebot.backends.twin.terrain.flat import Flat
from snakebot.errors import ConfigError, TerrainError


def parse_terrain(text: str, option: str = "terrain") -> Terrain:
    """The terrain ``text`` names, e.g. ``pegs:layout=row,spacing_m=0.15``, a built-in or a
    plugin's (``snakebot.terrains`` entry points) or one registered at runtime.

    ConfigError naming ``option`` and the key: an unknown terrain (listing them), an unknown key
    (listing the terrain's keys), or a value outside its accepted range (stating it).
    """
    name, _, rest = text.partition(":")
    name = name.strip()
    try:
        kind = get_terrain(name)
    except TerrainError as exc:
        if name in terrain_names():  # a plugin's terrain that would not load
            raise ConfigError(option, "", exc.reason) from None
        raise ConfigError(
            option,
            "",
            f"expected one of {', '.join(terrain_names())} (NAME:key=value,...), got {text!r}",
        ) from None
    params = kind.params()
    values: dict[str, Any] = {}
    for item in filter(None, (part.strip() for part in rest.split(","))):
        key, sep, raw = item.partition("=")
        key = key.strip()
        if not sep or key not in params:
            accepted = ", ".join(f"{k} ({p.accepted()})" for k, p in params.items()) or "none"
            raise ConfigError(
                option, key or item, f"{name} takes key=value with keys: {accepted}; got {item!r}"
            )
        values[key] = params[key].parse(option, key, raw)
    try:
        return kind(**values)
    except ConfigError as exc:  # a check between keys (the cliff's edge inside its depth)
        raise ConfigError(option, exc.key, exc.reason) from None


def as_terrain(value: Terrain | str | None) -> Terrain:
    """A Terrain from what a caller passed: a Terrain, ``--terrain`` text, or None (flat)."""
    if value is None:
        return Flat()
    if isinstance(value, str):
        return parse_terrain(value)
    return value
