"""The twin's terrains: seeded, built into the scene with MjSpec, chosen by
``--terrain NAME[:key=value,...]``."""

from snakebot.backends.twin.terrain.base import BodyShape, StartPose, Terrain
from snakebot.backends.twin.terrain.registry import (
    TERRAINS,
    as_terrain,
    parse_terrain,
)

__all__ = [
    "TERRAINS",
    "BodyShape",
    "StartPose",
    "Terrain",
    "as_terrain",
    "parse_terrain",
]
