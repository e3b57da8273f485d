"""The scene's floor plane and nothing else."""

from __future__ import annotations

from dataclasses import dataclass

from snakebot.backends.twin.terrain.base import Terrain


@dataclass(frozen=True)
class Flat(Terrain):
    """The flat floor; the twin's default."""

    name = "flat"
    summary = "the floor plane (default)"
