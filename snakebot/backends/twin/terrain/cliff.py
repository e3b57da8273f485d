"""Miller's rounded cliff (snakebot/backends/twin/cliff.py) as a ``--terrain`` entry."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco

from snakebot.backends.twin.cliff import Cliff
from snakebot.backends.twin.terrain.base import BodyShape, StartPose, Terrain, flat_start
from snakebot.backends.twin.terrain.params import param

_DEFAULT = Cliff()


@dataclass(frozen=True)
class CliffTerrain(Terrain):
    """A plateau the snake starts on, its front edge rounded, ``edge_m`` ahead of the head."""

    name = "cliff"
    summary = "Miller's rounded cliff: a plateau with a rounded front edge"
    plane_ground = False  # the snake starts on the plateau's boxes, not the floor plane

    edge_m: float = param(_DEFAULT.edge_m, 0.001, 10.0, "m", "head to the edge")
    height_m: float = param(_DEFAULT.height_m, 0.001, 1.0, "m", "plateau height")
    radius_m: float = param(_DEFAULT.radius_m, 0.001, 1.0, "m", "edge rounding radius")
    width_m: float = param(_DEFAULT.width_m, 0.01, 20.0, "m", "plateau width")
    depth_m: float = param(_DEFAULT.depth_m, 0.01, 20.0, "m", "plateau depth behind the edge")

    def __post_init__(self) -> None:
        super().__post_init__()
        self.cliff  # noqa: B018 - Cliff checks the keys against each other

    @property
    def cliff(self) -> Cliff:
        """The same cliff as the mass-spring bodies use."""
        return Cliff(self.edge_m, self.height_m, self.radius_m, self.width_m, self.depth_m)

    @classmethod
    def of(cls, cliff: Cliff) -> CliffTerrain:
        """The terrain for a ``Cliff``."""
        return cls(cliff.edge_m, cliff.height_m, cliff.radius_m, cliff.width_m, cliff.depth_m)

    def add_to(self, spec: mujoco.MjSpec, body: BodyShape) -> None:
        """The plateau and its rounded edge."""
        self.cliff.add_to(spec)

    def start_pose(self, body: BodyShape) -> StartPose:
        """On the plateau."""
        return flat_start(body, self.cliff.start_height_m)
