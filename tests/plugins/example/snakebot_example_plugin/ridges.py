"""A terrain plugin: low ridges across the snake's path, one every ``spacing_m`` ahead of it.

A terrain is a frozen dataclass subclassing snakebot's ``Terrain``: its fields are the
``--terrain ridges:key=value`` keys (each a ``param`` with bounds, unit and help), ``add_to``
adds the geometry to the scene's MjSpec and ``start_pose`` (here the default: straight on the
floor, head at the origin facing +x) places the snake.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco

from snakebot.backends.twin.terrain import BodyShape, Terrain
from snakebot.backends.twin.terrain.base import add_obstacle
from snakebot.backends.twin.terrain.params import param


@dataclass(frozen=True)
class Ridges(Terrain):
    """``count`` boxes ``height_m`` high across the path, the first ``spacing_m`` ahead of the
    head; the snake lies on the floor plane between them."""

    name = "ridges"
    summary = "low ridges across the path (example plugin)"

    count: int = param(3, 1, 50, "", "how many ridges", integer=True)
    height_m: float = param(0.01, 0.001, 0.1, "m", "ridge height")
    spacing_m: float = param(0.2, 0.05, 2.0, "m", "head to the first ridge, and between ridges")

    def add_to(self, spec: mujoco.MjSpec, body: BodyShape) -> None:
        """One thin box per ridge, 1 m wide."""
        for i in range(self.count):
            add_obstacle(
                spec.worldbody,
                name=f"ridge_{i}",
                type=mujoco.mjtGeom.mjGEOM_BOX,
                pos=[(i + 1) * self.spacing_m + body.radius_m, 0.0, self.height_m / 2],
                size=[0.005, 0.5, self.height_m / 2],
            )
