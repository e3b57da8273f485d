"""One step up across the snake's path (Fu & Li 2020: steps up to a third of a body length)."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco

from snakebot.backends.twin.terrain.base import BodyShape, Terrain, add_obstacle
from snakebot.backends.twin.terrain.params import param


@dataclass(frozen=True)
class Step(Terrain):
    """A box ``height_m`` high whose face lies ``distance_m`` ahead of the head, ``depth_m``
    deep along +x and ``width_m`` across; the snake starts on the floor in front of it."""

    name = "step"
    summary = "a step up in front of the head (Fu & Li 2020)"
    plane_ground = False

    height_m: float = param(0.05, 0.005, 0.5, "m", "step height")
    distance_m: float = param(0.05, 0.0, 2.0, "m", "head to the step's face")
    depth_m: float = param(2.0, 0.1, 20.0, "m", "length of the top along +x")
    width_m: float = param(2.0, 0.1, 20.0, "m", "width across")

    def add_to(self, spec: mujoco.MjSpec, body: BodyShape) -> None:
        """One box, its face at x = distance_m + the capsule radius (so the head clears it)."""
        face = self.distance_m + body.radius_m
        add_obstacle(
            spec.worldbody,
            name="step",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            pos=[face + self.depth_m / 2, 0.0, self.height_m / 2],
            size=[self.depth_m / 2, self.width_m / 2, self.height_m / 2],
        )
