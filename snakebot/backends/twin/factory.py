"""``make_twin``: the twin backend's factory in the backend registry (name ``twin``, alias ``sim``).

Options arrive as the command line gives them (text, ``True`` for a flag) or already typed; a
bad value is a ConfigError whose source is the option's name.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from snakebot.backends.twin.model_builder import GroundFriction
from snakebot.config import RobotConfig
from snakebot.config.body import BodyConfig
from snakebot.errors import ConfigError

if TYPE_CHECKING:
    from snakebot.backends.base import Backend
    from snakebot.backends.twin.friction.scale import FrictionModel
    from snakebot.backends.twin.terrain import Terrain

FRICTION_MODELS = ("auto", "pairs", "scale")


def make_twin(
    robot: RobotConfig | BodyConfig,
    *,
    friction: GroundFriction | str | tuple[float, float] | float | None = None,
    terrain: Terrain | str | None = None,
    friction_model: str | None = None,
    realtime: bool = False,
    directional: bool | str | None = None,
    timestep_s: float | None = None,
) -> Backend:
    """The MuJoCo twin of ``robot``, unconnected: a TwinBackend for a servo chain, the soft-body
    twin for a mass-spring body (``directional`` applies to those only).

    ``friction``: AXIAL,LATERAL or FORWARD,BACKWARD,LATERAL (text, a pair or a GroundFriction)
    over the robot's ground model; ``terrain``: ``NAME[:key=value,...]`` (a terrain of
    ``snakebot.backends.terrains``: docs/terrain.md; a mass-spring body takes flat or cliff) or a
    Terrain; ``friction_model``: auto, pairs or scale (None: the robot file's);
    ``realtime``: pace to the wall clock; ``timestep_s``: the physics step in s. ConfigError
    (source: the option's name) for a bad value.
    """
    if isinstance(robot, BodyConfig):
        if timestep_s is not None:
            raise ConfigError("timestep_s", "", "a mass-spring body's timestep is in its body file")
        from snakebot.backends.softbody.factory import make_softbody

        if friction_model is not None:
            raise ConfigError("friction_model", "", "applies to the rigid twin only")
        return make_softbody(
            robot,
            friction=friction,
            terrain=terrain,
            realtime=realtime,
            directional=directional,
        )
    if not isinstance(robot, RobotConfig):
        raise ConfigError(
            "robot", "", f"the twin needs a RobotConfig or a BodyConfig, got {type(robot).__name__}"
        )
    if directional is not None:
        raise ConfigError("directional", "", "applies to mass-spring bodies only")
    from snakebot.backends.twin.backend import TwinBackend

    return TwinBackend(
        robot,
        friction=ground_friction_option(friction),
        terrain=terrain_option(terrain, robot),
        friction_model=friction_model_option(friction_model),
        realtime=bool(realtime),
        timestep_s=timestep_s,
    )


def ground_friction_option(
    value: GroundFriction | str | tuple[float, float] | float | None,
) -> GroundFriction | None:
    """The ``friction`` option as a GroundFriction: ``"AXIAL,LATERAL"``, a pair, one number
    (isotropic) or a GroundFriction; ConfigError (source ``friction``) otherwise."""
    if value is None or isinstance(value, GroundFriction):
        return value
    if isinstance(value, str):
        return GroundFriction.parse(value, option="friction")
    if isinstance(value, int | float):
        value = (float(value), float(value))
    try:
        axial, lateral = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ConfigError(
            "friction", "", f"expected AXIAL,LATERAL (two numbers >= 0), got {value!r}"
        ) from None
    return GroundFriction.parse(f"{axial!r},{lateral!r}", option="friction")


def terrain_option(value: Terrain | str | None, robot: RobotConfig) -> Terrain:
    """The ``terrain`` option as a Terrain checked against ``robot``'s size: ``"flat"``,
    ``"NAME[:key=value,...]"`` or a Terrain (None: flat); ConfigError (source
    ``terrain``) naming the key otherwise."""
    from snakebot.backends.twin.model_builder import body_shape
    from snakebot.backends.twin.terrain import Terrain, as_terrain, parse_terrain

    if isinstance(value, str):
        terrain = parse_terrain(value, option="terrain")
    elif value is None or isinstance(value, Terrain):
        terrain = as_terrain(value)
    else:
        raise ConfigError(
            "terrain", "", f"expected NAME[:key=value,...] or a Terrain, got {value!r}"
        )
    terrain.check(body_shape(robot))
    return terrain


def friction_model_option(value: str | None) -> FrictionModel | None:
    """The ``friction_model`` option: auto, pairs or scale (None: the robot file's)."""
    if value is None or value in FRICTION_MODELS:
        return value  # type: ignore[return-value]
    raise ConfigError(
        "friction_model", "", f"expected one of {', '.join(FRICTION_MODELS)}, got {value!r}"
    )
