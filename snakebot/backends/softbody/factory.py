"""``make_softbody``: the mass-spring body's factory in the backend registry (name ``softbody``;
the ``twin`` backend hands bodies to it too)."""

from __future__ import annotations

import math

from snakebot.backends.softbody.backend import SoftBodyBackend
from snakebot.backends.terrains import BODY_TERRAINS
from snakebot.backends.twin.model_builder import GroundFriction
from snakebot.backends.twin.terrain.base import Terrain
from snakebot.backends.twin.terrain.cliff import Cliff
from snakebot.backends.twin.terrain.flat import Flat
from snakebot.backends.twin.terrain.registry import parse_terrain
from snakebot.config.body import BodyConfig
from snakebot.errors import ConfigError


def make_softbody(
    body: BodyConfig,
    *,
    friction: float | str | GroundFriction | tuple[float, float] | None = None,
    terrain: Terrain | str | None = None,
    realtime: bool = False,
    directional: bool | str | None = None,
) -> SoftBodyBackend:
    """The soft-body twin of ``body``, unconnected.

    ``friction``: the floor's coefficient (a number, ``"MU"`` or an isotropic pair);
    ``directional``: Miller's directional friction (True/False or ``"on"``/``"off"``; default
    the body file's); ``terrain`` and ``realtime`` as the twin's. ConfigError for a bad value,
    or when ``body`` is a servo robot rather than a mass-spring body.
    """
    if not isinstance(body, BodyConfig):
        name = getattr(body, "name", type(body).__name__)
        raise ConfigError(
            str(name),
            "",
            "is not a mass-spring body: the softbody backend drives "
            "firmware_configs/bodies/ files (the twin backend drives servo robots)",
        )
    return SoftBodyBackend(
        body,
        friction=floor_friction_option(friction),
        directional=directional_option(directional),
        terrain=body_terrain_option(terrain),
        realtime=bool(realtime),
    )


def parse_floor_friction(text: str, option: str = "friction") -> float:
    """A body's floor friction: ``MU``, or ``MU,MU`` (the twin's AXIAL,LATERAL with both equal);
    ConfigError whose source is ``option`` otherwise."""
    parts = [p.strip() for p in text.split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if not 1 <= len(values) <= 2 or not all(math.isfinite(v) and v >= 0 for v in values):
        raise ConfigError(option, "", f"expected one friction coefficient >= 0, got {text!r}")
    if len(values) == 2 and values[0] != values[1]:
        raise ConfigError(
            option,
            "",
            f"a mass-spring body's floor is isotropic: give one number, got {text!r} "
            "(forward/backward asymmetry is directional friction)",
        )
    return values[0]


def floor_friction_option(
    value: float | str | GroundFriction | tuple[float, float] | None,
) -> float | None:
    """The ``friction`` option of a body as one coefficient; ConfigError (source ``friction``)."""
    if value is None:
        return None
    if isinstance(value, str):
        return parse_floor_friction(value)
    if isinstance(value, GroundFriction):
        value = (value.axial, value.lateral)
    if isinstance(value, int | float):
        return parse_floor_friction(repr(float(value)))
    try:
        return parse_floor_friction(",".join(repr(float(v)) for v in value))
    except (TypeError, ValueError) as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError("friction", "", f"expected a number >= 0, got {value!r}") from None


def directional_option(value: bool | str | None) -> bool | None:
    """``directional``: True/False, or ``"on"``/``"off"`` as the command line says it."""
    if value is None or isinstance(value, bool):
        return value
    if value in ("on", "off"):
        return value == "on"
    raise ConfigError("directional", "", f"expected on or off, got {value!r}")


def body_terrain_option(value: Terrain | str | None, option: str = "terrain") -> Cliff | None:
    """A mass-spring body's ground: flat (None) or a Cliff, from ``--terrain`` text (parsed by
    the one ``parse_terrain``) or a Terrain; ConfigError (source ``option``) for any other
    terrain, naming the ones a body takes."""
    terrain = parse_terrain(value, option) if isinstance(value, str) else value
    if terrain is None or isinstance(terrain, Flat):
        return None
    if isinstance(terrain, Cliff):
        return terrain
    name = terrain.name if isinstance(terrain, Terrain) else repr(terrain)
    raise ConfigError(
        option,
        "",
        f"a mass-spring body lies on {' or '.join(BODY_TERRAINS)} (cliff:key=value,...), not "
        f"{name}; the rigid twin takes every terrain",
    )
