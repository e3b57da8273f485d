"""A vertical pole beside the snake, for rolling and climbing gaits (Choset's group)."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco

from snakebot.backends.twin.terrain.base import BodyShape, Terrain, add_obstacle
from snakebot.backends.twin.terrain.params import param

_GAP_M = 0.005


@dataclass(frozen=True)
class Pole(Terrain):
    """A cylinder of ``diameter_m`` and ``height_m`` standing on the floor beside the middle of
    the body (on its +y side, ``gap_m`` clear of it)."""

    name = "pole"
    summary = "a vertical pole beside the body (rolling, climbing)"

    diameter_m: float = param(0.1, 0.01, 1.0, "m", "pole diameter")
    height_m: float = param(1.0, 0.05, 5.0, "m", "pole height")
    gap_m: float = param(_GAP_M, 0.0, 1.0, "m", "clearance between body and pole")

    def add_to(self, spec: mujoco.MjSpec, body: BodyShape) -> None:
        """The pole at the body's middle, beside it."""
        radius = self.diameter_m / 2
        add_obstacle(
            spec.worldbody,
            name="pole",
            type=mujoco.mjtGeom.mjGEOM_CYLINDER,
            pos=[-body.body_length_m / 2, body.radius_m + self.gap_m + radius, self.height_m / 2],
            size=[radius, self.height_m / 2, 0.0],
        )
