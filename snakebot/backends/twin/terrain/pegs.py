"""Vertical pegs: a row across the path (Rieser, Schiebel & Goldman) or a random field
(obstacle-aided locomotion, Liljebäck & Transeth)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from snakebot.backends.twin.terrain.base import BodyShape, Terrain, add_obstacle
from snakebot.backends.twin.terrain.params import param

_CLEARANCE_M = 0.005
_PLACEMENT_TRIES = 50


@dataclass(frozen=True)
class Pegs(Terrain):
    """Cylinders ``radius_m`` wide and ``height_m`` tall on the floor.

    ``field``: ``density`` pegs per m² placed at random (``seed``) in the square of half-side
    ``extent_m`` around the head, no two centres closer than ``spacing_m``. ``lattice``: a square
    lattice of ``spacing_m`` whose rows run along x, the body starting in the lane between two
    rows. ``row``: one row across the path (along y), ``distance_m`` ahead of the head, centres
    ``spacing_m`` apart, ``extent_m`` to either side. No peg overlaps the body's start. Peg
    contacts have friction ``friction``: 0 (the default) is a smooth, greased peg that pushes
    but does not grip; docs/terrain.md shows how grip jams a snake between pegs.
    """

    name = "pegs"
    summary = "a random peg field, a peg lattice or a row (obstacle-aided locomotion)"

    layout: str = param(
        "field", choices=("field", "lattice", "row"), help="a random field, a lattice or one row"
    )
    spacing_m: float = param(
        0.09, 0.01, 5.0, "m", "row, lattice: centre spacing; field: least spacing"
    )
    radius_m: float = param(0.005, 0.002, 0.5, "m", "peg radius")
    density: float = param(40.0, 0.01, 2000.0, "1/m^2", "field: pegs per square metre")
    seed: int = param(0, 0, 2**31 - 1, "", "field: random layout", integer=True)
    height_m: float = param(0.1, 0.01, 2.0, "m", "peg height")
    distance_m: float = param(0.1, 0.0, 10.0, "m", "row: head to the row")
    extent_m: float = param(2.0, 0.1, 50.0, "m", "half-size of the field, half-length of a row")
    friction: float = param(0.0, 0.0, 2.0, "", "peg friction coefficient")

    def centres(self, body: BodyShape) -> np.ndarray:
        """Peg centres (P, 2) in m on the floor."""
        if self.layout == "row":
            count = int(self.extent_m // self.spacing_m)
            y = self.spacing_m * np.arange(-count, count + 1)
            x = np.full_like(y, self.distance_m + body.radius_m + self.radius_m)
            return np.column_stack([x, y])
        if self.layout == "lattice":
            return self._lattice(body)
        rng = np.random.default_rng(self.seed)
        wanted = round(self.density * (2 * self.extent_m) ** 2)
        keep_out = self.radius_m + body.radius_m + _CLEARANCE_M
        placed: list[np.ndarray] = []
        for _ in range(wanted * _PLACEMENT_TRIES):
            if len(placed) == wanted:
                break
            point = rng.uniform(-self.extent_m, self.extent_m, size=2)
            # Clear of the body's start: the segment from the tail (-L, 0) to the head (0, 0).
            along = min(max(point[0], -body.body_length_m), 0.0)
            if math.hypot(point[0] - along, point[1]) < keep_out:
                continue
            if placed and np.min(np.hypot(*(np.array(placed) - point).T)) < self.spacing_m:
                continue
            placed.append(point)
        return np.array(placed).reshape(-1, 2)

    def _lattice(self, body: BodyShape) -> np.ndarray:
        """A square lattice whose rows run along x at y = (j + 1/2) spacing: the body starts
        in the lane between the two middle rows; pegs overlapping its start are left out."""
        count = int(self.extent_m / self.spacing_m + 1e-9)
        steps = self.spacing_m * np.arange(-count, count + 1)
        x, y = np.meshgrid(steps, steps[:-1] + self.spacing_m / 2)
        points = np.column_stack([x.ravel(), y.ravel()])
        along = np.clip(points[:, 0], -body.body_length_m, 0.0)
        clear = np.hypot(points[:, 0] - along, points[:, 1])
        kept: np.ndarray = points[clear >= self.radius_m + body.radius_m + _CLEARANCE_M]
        return kept

    def add_to(self, spec: mujoco.MjSpec, body: BodyShape) -> None:
        """One cylinder per centre."""
        for index, (x, y) in enumerate(self.centres(body)):
            add_obstacle(
                spec.worldbody,
                name=f"peg{index}",
                type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                pos=[float(x), float(y), self.height_m / 2],
                size=[self.radius_m, self.height_m / 2, 0.0],
                friction=[self.friction, 0.005, 0.0001],
                priority=1,
            )
