"""A straight pipe along x, the snake inside it (Enner, Rollinson & Choset: snakes in pipes).

MuJoCo convexifies meshes, so a pipe is a ring of boxes (learning-softbody-terrain.md §3.1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco

from snakebot.backends.twin.terrain.base import (
    BodyShape,
    StartPose,
    Terrain,
    add_obstacle,
    quat_about,
)
from snakebot.backends.twin.terrain.params import param
from snakebot.errors import ConfigError

_TAIL_ROOM_M = 0.2


@dataclass(frozen=True)
class Pipe(Terrain):
    """``sides`` boxes ``wall_m`` thick around an inner diameter of ``inner_diameter_m``, lying
    on the floor; it starts ``0.2 m`` behind the tail and runs ``length_m`` along +x."""

    name = "pipe"
    summary = "the snake inside a straight pipe"
    plane_ground = False

    inner_diameter_m: float = param(0.15, 0.02, 2.0, "m", "inside diameter")
    length_m: float = param(3.0, 0.3, 50.0, "m", "pipe length")
    wall_m: float = param(0.01, 0.002, 0.2, "m", "wall thickness")
    sides: int = param(16, 6, 64, "", "boxes around the ring", integer=True)

    def check(self, body: BodyShape) -> None:
        """The links must fit inside, and the pipe must be longer than the snake."""
        if self.inner_diameter_m <= 2.2 * body.radius_m:
            raise ConfigError(
                "terrain",
                "inner_diameter_m",
                f"expected more than 2.2 link radii ({2.2 * body.radius_m:.3f} m) so the links "
                f"fit, got {self.inner_diameter_m:g}",
            )
        if self.length_m <= body.body_length_m + 2 * _TAIL_ROOM_M:
            raise ConfigError(
                "terrain",
                "length_m",
                f"expected more than the body length + 0.4 m "
                f"({body.body_length_m + 2 * _TAIL_ROOM_M:.2f} m), got {self.length_m:g}",
            )

    @property
    def _axis_z_m(self) -> float:
        return self.inner_diameter_m / 2 + self.wall_m

    def add_to(self, spec: mujoco.MjSpec, body: BodyShape) -> None:
        """The ring of boxes; one lies at the bottom, so the floor inside is flat."""
        inner = self.inner_diameter_m / 2
        start = -body.body_length_m - _TAIL_ROOM_M
        half_width = (inner + self.wall_m) * math.tan(math.pi / self.sides)
        for k in range(self.sides):
            theta = -math.pi / 2 + 2 * math.pi * k / self.sides
            centre = inner + self.wall_m / 2
            add_obstacle(
                spec.worldbody,
                name=f"pipe{k}",
                type=mujoco.mjtGeom.mjGEOM_BOX,
                pos=[
                    start + self.length_m / 2,
                    centre * math.cos(theta),
                    self._axis_z_m + centre * math.sin(theta),
                ],
                quat=quat_about((1.0, 0.0, 0.0), theta - math.pi / 2),
                size=[self.length_m / 2, half_width, self.wall_m / 2],
                rgba=[0.55, 0.5, 0.42, 0.35],
            )

    def start_pose(self, body: BodyShape) -> StartPose:
        """On the pipe's inner floor, along its axis."""
        return StartPose((0.0, 0.0, self.wall_m + body.radius_m + 1e-3))
