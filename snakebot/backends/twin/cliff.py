"""Miller's rounded cliff: a raised plateau whose front edge is a quarter cylinder.

The body starts on the plateau, head at x = 0 facing +x; the edge lies ``edge_m`` ahead of the
head. In the x-z plane the plateau's top runs at z = ``height_m`` up to x = edge - radius, rounds
over a cylinder of ``radius_m`` (axis along y) and drops vertically to the floor at x = edge.
Any MjSpec can take one (``add_to``), the rigid twin's and the mass-spring body's alike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import mujoco

from snakebot.errors import ConfigError

# Contact bits: 1 reaches the scene floor's partners (mass points), 2 the rigid twin's modules.
_TERRAIN_BITS = 1 | 2


@dataclass(frozen=True)
class Cliff:
    """Plateau height, edge rounding and position in m; ``width_m`` across, ``depth_m`` back."""

    edge_m: float = 0.1
    height_m: float = 0.04
    radius_m: float = 0.02
    width_m: float = 2.0
    depth_m: float = 2.0

    def __post_init__(self) -> None:
        for item in fields(self):
            value = getattr(self, item.name)
            if not (math.isfinite(value) and value > 0):
                raise ConfigError("terrain", item.name, f"expected a positive number, got {value}")
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

    def add_to(self, spec: mujoco.MjSpec) -> None:
        """Add the plateau (two boxes) and the rounded edge (a cylinder) to ``spec``'s world."""
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
            world.add_geom(
                name=name,
                type=mujoco.mjtGeom.mjGEOM_BOX,
                pos=[(x0 + x1) / 2, 0.0, (z0 + z1) / 2],
                size=[(x1 - x0) / 2, self.width_m / 2, (z1 - z0) / 2],
                contype=_TERRAIN_BITS,
                conaffinity=_TERRAIN_BITS,
                rgba=[0.55, 0.5, 0.42, 1],
            )
        world.add_geom(
            name="cliff_edge",
            type=mujoco.mjtGeom.mjGEOM_CYLINDER,
            pos=[top_end, 0.0, height - radius],
            quat=[math.sqrt(0.5), math.sqrt(0.5), 0.0, 0.0],  # cylinder axis z -> y
            size=[radius, self.width_m / 2, 0.0],
            contype=_TERRAIN_BITS,
            conaffinity=_TERRAIN_BITS,
            rgba=[0.55, 0.5, 0.42, 1],
        )


TERRAINS = ("flat", "cliff")


def parse_terrain(text: str, option: str = "terrain") -> Cliff | None:
    """``flat`` (None) or ``cliff[:key=value,...]`` with Cliff's fields, e.g.
    ``cliff:edge_m=0.1,height_m=0.05``; ConfigError naming what was expected otherwise."""
    name, _, rest = text.partition(":")
    name = name.strip()
    if name not in TERRAINS:
        raise ConfigError(
            option, "", f"expected one of {', '.join(TERRAINS)} (cliff:key=value,...), got {text!r}"
        )
    if name == "flat":
        if rest.strip():
            raise ConfigError(option, "", "flat takes no parameters")
        return None
    known = [item.name for item in fields(Cliff)]
    values: dict[str, float] = {}
    for item in filter(None, (part.strip() for part in rest.split(","))):
        key, sep, raw = item.partition("=")
        key = key.strip()
        if not sep or key not in known:
            raise ConfigError(
                option, key, f"expected key=value with a key from {', '.join(known)}, got {item!r}"
            )
        try:
            values[key] = float(raw)
        except ValueError:
            raise ConfigError(option, key, f"expected a number in m, got {raw!r}") from None
    try:
        return Cliff(**values)
    except ConfigError as exc:
        raise ConfigError(option, exc.key, exc.reason) from None
