"""``--terrain`` and ``--friction-model`` for the commands that run the rigid twin (run, tune).

A bad terrain name, key or value is a usage error (exit 2) naming the key and what it accepts.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any, cast

from snakebot.errors import ConfigError, UsageError

if TYPE_CHECKING:
    from snakebot.backends.twin.friction.scale import FrictionModel
    from snakebot.backends.twin.terrain import Terrain
    from snakebot.config import RobotConfig

FRICTION_MODEL_CHOICES = ("auto", "pairs", "scale")

FRICTION_MODEL_HELP = (
    "twin ground friction: pairs (MuJoCo capsule-plane pairs, fast, floor plane only), scale "
    "(directional friction from contact forces in each link's frame, any ground) or auto "
    "(pairs where the snake lies on the floor plane, scale on any other ground: docs/terrain.md "
    "says which terrain is which); default: the robot file's twin.friction_model, else auto"
)


def terrain_help() -> str:
    """``--terrain``'s help, generated from the terrain registry (plugins included)."""
    from snakebot.backends.terrains import terrain_help as registry_help

    return "twin terrain: " + registry_help()


def add_terrain_options(parser: argparse.ArgumentParser, *, terrain: bool = True) -> None:
    """Add ``--terrain`` (unless the command has it already) and ``--friction-model``."""
    if terrain:
        parser.add_argument("--terrain", metavar="NAME[:KEY=VALUE,...]", help=terrain_help())
    parser.add_argument(
        "--friction-model", choices=FRICTION_MODEL_CHOICES, help=FRICTION_MODEL_HELP
    )


def twin_terrain(args: argparse.Namespace, robot: RobotConfig | None = None) -> Terrain | None:
    """``--terrain`` parsed for the rigid twin (and checked against ``robot``'s size if given);
    UsageError (exit 2) naming the key if bad."""
    text = getattr(args, "terrain", None)
    if not text:
        return None
    from snakebot.backends.twin.model_builder import body_shape
    from snakebot.backends.twin.terrain import parse_terrain

    try:
        terrain = parse_terrain(text, "--terrain")
        if robot is not None:
            terrain.check(body_shape(robot))
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    return terrain


def friction_model(args: argparse.Namespace) -> FrictionModel | None:
    """``--friction-model``, or None for the robot file's choice."""
    return cast("FrictionModel | None", getattr(args, "friction_model", None))


def twin_ground(args: argparse.Namespace, robot: RobotConfig | None = None) -> dict[str, Any]:
    """Keyword arguments for TwinBackend: ``terrain`` and ``friction_model`` from the options."""
    return {"terrain": twin_terrain(args, robot), "friction_model": friction_model(args)}


def refuse_friction_model(args: argparse.Namespace, why: str) -> None:
    """UsageError if ``--friction-model`` was given where no rigid twin runs."""
    if getattr(args, "friction_model", None):
        raise UsageError(f"--friction-model {why}")
