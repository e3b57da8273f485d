"""What every terrain provides: geometry added to an MjSpec, the snake's start pose, and whether
its ground is the floor plane (where capsule pairs keep body-aligned friction)."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any, ClassVar

import mujoco

from snakebot.backends.twin.terrain.params import Param

# Contact bits. The ground the snake lies on (the floor plane, a height field) is bit 1 only:
# with capsule pairs the links (bit 2) reach it only through the pairs. Obstacles carry 1|2 and
# touch the links directly. The scale-friction model gives the links bit 1 as well.
GROUND_BITS = 1
OBSTACLE_BITS = 1 | 2
OBSTACLE_RGBA = (0.55, 0.5, 0.42, 1.0)


@dataclass(frozen=True)
class BodyShape:
    """The chain a terrain is laid out for: link count, link pitch and capsule radius in m."""

    link_count: int
    link_length_m: float
    radius_m: float

    @property
    def body_length_m(self) -> float:
        """Head to tail, m."""
        return self.link_count * self.link_length_m


@dataclass(frozen=True)
class StartPose:
    """Where the head starts: position (m, world) and orientation (w, x, y, z quaternion).

    The chain trails the head along the head's -x axis.
    """

    pos: tuple[float, float, float]
    quat: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)


def flat_start(body: BodyShape, ground_z_m: float = 0.0) -> StartPose:
    """Straight, head at the origin facing +x, lying on ground at ``ground_z_m``."""
    return StartPose((0.0, 0.0, ground_z_m + body.radius_m + 1e-3))


@dataclass(frozen=True)
class Terrain:
    """Base of every terrain: a frozen dataclass whose fields are its ``--terrain`` keys.

    Each field carries a :class:`Param` (bounds, unit, help) in its metadata; the registry
    parses ``NAME:key=value,...`` from them. ``plane_ground`` says the snake lies on the floor
    plane, so friction model "auto" picks capsule pairs; otherwise the scale model.
    """

    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    plane_ground: ClassVar[bool] = True
    pair_geom: ClassVar[str] = "floor"

    def __post_init__(self) -> None:
        for key, spec in self.params().items():
            spec.check("terrain", key, getattr(self, key))

    def check(self, body: BodyShape) -> None:
        """Raise ConfigError naming a key if this terrain cannot host ``body``."""

    def add_to(self, spec: mujoco.MjSpec, body: BodyShape) -> None:
        """Add this terrain's geometry to ``spec`` (which holds the scene's "floor" plane)."""

    def start_pose(self, body: BodyShape) -> StartPose:
        """The head's start pose on this terrain."""
        return flat_start(body)

    @classmethod
    def params(cls) -> dict[str, Param]:
        """The keys ``--terrain NAME:key=value`` takes, in order."""
        return {item.name: item.metadata["param"] for item in fields(cls)}

    def spec_text(self) -> str:
        """The ``--terrain`` text that rebuilds this terrain."""
        values = [f"{key}={_fmt(getattr(self, key))}" for key in self.params()]
        return self.name + (":" + ",".join(values) if values else "")

    def as_dict(self) -> dict[str, Any]:
        """Name and parameters, for summaries and reports."""
        return {"name": self.name, **{key: getattr(self, key) for key in self.params()}}


def _fmt(value: object) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def quat_about(axis: tuple[float, float, float], angle_rad: float) -> list[float]:
    """Unit quaternion (w, x, y, z) of a rotation by ``angle_rad`` about unit ``axis``."""
    s = math.sin(angle_rad / 2)
    return [math.cos(angle_rad / 2), axis[0] * s, axis[1] * s, axis[2] * s]


def add_obstacle(world: mujoco.MjsBody, **attributes: Any) -> mujoco.MjsGeom:
    """A static obstacle geom that touches both the rigid links and mass points."""
    attributes.setdefault("rgba", list(OBSTACLE_RGBA))
    return world.add_geom(contype=OBSTACLE_BITS, conaffinity=OBSTACLE_BITS, **attributes)
