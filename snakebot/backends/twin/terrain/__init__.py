"""The twin's terrains: seeded, built into the scene with MjSpec, chosen by
``--terrain NAME[:key=value,...]``; by name in ``snakebot.backends.terrains`` (plugins too)."""

from snakebot.backends.terrains import (
    BUILT_IN_TERRAINS,
    TERRAINS,
    register_terrain,
    terrain_names,
)
from snakebot.backends.twin.terrain.base import BodyShape, StartPose, Terrain
from snakebot.backends.twin.terrain.cliff import Cliff
from snakebot.backends.twin.terrain.registry import as_terrain, parse_terrain

__all__ = [
    "BUILT_IN_TERRAINS",
    "TERRAINS",
    "BodyShape",
    "Cliff",
    "StartPose",
    "Terrain",
    "as_terrain",
    "parse_terrain",
    "register_terrain",
    "terrain_names",
]
