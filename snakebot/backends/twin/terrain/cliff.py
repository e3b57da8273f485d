"""Miller's rounded cliff: a raised plateau whose front edge is a quarter cylinder.

The body starts on the plateau, head at x = 0 facing +x; the edge lies ``edge_m`` ahead of the
head. In the x-z plane the plateau's top runs at z = ``height_m`` up to x = edge - radius, rounds
over a cylinder of ``radius_m`` (axis along y) and drops vertically to the floor at x = edge.
Any MjSpec can take one (``add_to``), the rigid twin's and the mass-spring body's alike: the one
terrain both bodies lie on besides the flat floor.
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
    flat_start,
)
from snakebot.backends.twin.terrain.params import param
from snakebot.errors import ConfigError


@dataclass(frozen=True)
class Cliff(Terrain):
    """A plateau the snake starts on, its front edge rounded, ``edge_m`` ahead of the head.

    Plateau height, edge rounding and position in m; ``width_m`` across, ``depth_m`` back.
    """

    name = "cliff"
    summary = "Miller's rounded cliff: a plateau with a rounded front edge"
    plane_ground = False  # the snake starts on the plateau's boxes, not the floor plane

    edge_m: float = param(0.1, 0.001, 10.0, "m", "head to the edge")
    height_m: float = param(0.04, 0.001, 1.0, "m", "plateau height")
    radius_m: float = param(0.02, 0.001, 1.0, "m", "edge rounding radius")
    width_m: float = param(2.0, 0.01, 20.0, "m", "plateau width")
    depth_m: float = param(2.0, 0.01, 20.0, "m", "plateau depth behind the edge")

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.radius_m > self.height_m:
            raise ConfigError(
                "terrain",
                "radius_m",
                f"the edge radius {self.radius_m} m exceeds the height {self.height_m} m",
            )
        if self.radius_m >= self.edge_m or self.depth_m <= self.edge_m:
            raise ConfigError(
                "terrain",
                "edge_m",
                "the head must start on the flat top: need radius_m < "
                f"edge_m < depth_m, got {self.radius_m}, {self.edge_m}, {self.depth_m}",
            )

    @property
    def start_height_m(self) -> float:
        """Height of the ground under the body's start: the plateau's top."""
        return self.height_m

    def add_to(self, spec: mujoco.MjSpec, body: BodyShape | None = None) -> None:
        """Add the plateau (two boxes) and the rounded edge (a cylinder) to ``spec``'s world;
        they touch the rigid links and the mass points alike (``body`` is not needed)."""
        edge, height, radius = self.edge_m, self.height_m, self.radius_m
        back = edge - self.depth_m
        top_end = edge - radius
        world = spec.worldbody
        parts = (
            ("cliff_top", (back, top_end), (0.0, height)),
            ("cliff_face", (top_end, edge), (0.0, height - radius)),
        )
        for name, (x0, x1), (z0, z1) in parts:
            if x1 - x0 <= 0 or z1 - z0 <= 0:
                continue
            add_obstacle(
                world,
                name=name,
                type=mujoco.mjtGeom.mjGEOM_BOX,
                pos=[(x0 + x1) / 2, 0.0, (z0 + z1) / 2],
                size=[(x1 - x0) / 2, self.width_m / 2, (z1 - z0) / 2],
            )
        add_obstacle(
            world,
            name="cliff_edge",
            type=mujoco.mjtGeom.mjGEOM_CYLINDER,
            pos=[top_end, 0.0, height - radius],
            quat=[math.sqrt(0.5), math.sqrt(0.5), 0.0, 0.0],  # cylinder axis z -> y
            size=[radius, self.width_m / 2, 0.0],
        )

    def start_pose(self, body: BodyShape) -> StartPose:
        """On the plateau."""
        return flat_start(body, self.start_height_m)
