"""Every terrain by name, and ``NAME[:key=value,...]`` parsing against their declared keys."""

from __future__ import annotations

from typing import Any

from snakebot.backends.twin.cliff import Cliff
from snakebot.backends.twin.terrain.base import Terrain
from snakebot.backends.twin.terrain.cliff import CliffTerrain
from snakebot.backends.twin.terrain.flat import Flat
from snakebot.backends.twin.terrain.pegs import Pegs
from snakebot.backends.twin.terrain.pipe import Pipe
from snakebot.backends.twin.terrain.pole import Pole
from snakebot.backends.twin.terrain.rough import Rough
from snakebot.backends.twin.terrain.slope import Slope
from snakebot.backends.twin.terrain.step import Step
from snakebot.errors import ConfigError

TERRAINS: dict[str, type[Terrain]] = {
    kind.name: kind for kind in (Flat, Slope, Pegs, Rough, Step, Pipe, Pole, CliffTerrain)
}


def parse_terrain(text: str, option: str = "terrain") -> Terrain:
    """The terrain ``text`` names, e.g. ``pegs:layout=row,spacing_m=0.15``.

    ConfigError naming ``option`` and the key: an unknown terrain (listing them), an unknown key
    (listing the terrain's keys), or a value outside its accepted range (stating it).
    """
    name, _, rest = text.partition(":")
    name = name.strip()
    kind = TERRAINS.get(name)
    if kind is None:
        raise ConfigError(
            option, "", f"expected one of {', '.join(TERRAINS)} (NAME:key=value,...), got {text!r}"
        )
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
    return kind(**values)


def as_terrain(value: Terrain | Cliff | str | None) -> Terrain:
    """A Terrain from what a caller passed: a Terrain, a Cliff, ``--terrain`` text, or None
    (flat)."""
    if value is None:
        return Flat()
    if isinstance(value, str):
        return parse_terrain(value)
    if isinstance(value, Cliff):
        return CliffTerrain.of(value)
    return value
