"""Rough ground: a seeded height field with Gaussian-correlated heights."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from snakebot.backends.twin.terrain.base import GROUND_BITS, BodyShape, StartPose, Terrain
from snakebot.backends.twin.terrain.params import param
from snakebot.errors import ConfigError

_BASE_M = 0.05  # the field's solid thickness below its lowest point
_MIN_RELIEF_M = 1e-4  # MuJoCo needs a positive height scale; a flat field gets this much


@dataclass(frozen=True)
class Rough(Terrain):
    """A square height field of half-side ``size_m`` and cells of ``cell_m``: white noise
    (``seed``) smoothed by a Gaussian of ``correlation_m``, scaled to a standard deviation of
    ``roughness_m`` about z = 0. ``roughness_m=0`` is a flat height field."""

    name = "rough"
    summary = "a rough height field (roughness_m=0: a flat one)"
    plane_ground = False
    pair_geom = "rough"

    roughness_m: float = param(0.01, 0.0, 0.1, "m", "standard deviation of the height")
    correlation_m: float = param(0.1, 0.005, 2.0, "m", "correlation length")
    seed: int = param(0, 0, 2**31 - 1, "", "random heights", integer=True)
    size_m: float = param(3.0, 0.2, 25.0, "m", "half-side of the square field")
    cell_m: float = param(0.02, 0.005, 0.2, "m", "cell size")

    def check(self, body: BodyShape) -> None:
        """The body must start on the field."""
        if self.size_m <= body.body_length_m + 0.1:
            raise ConfigError(
                "terrain",
                "size_m",
                f"expected more than the body length + 0.1 m "
                f"({body.body_length_m + 0.1:.2f} m), got {self.size_m:g}",
            )

    def heights(self) -> np.ndarray:
        """Heights (n, n) in m, rows along y from -size to +size (MuJoCo's row order)."""
        count = 2 * round(self.size_m / self.cell_m) + 1
        if self.roughness_m == 0:
            return np.zeros((count, count))
        rng = np.random.default_rng(self.seed)
        noise = rng.standard_normal((count, count))
        frequency = np.fft.fftfreq(count, d=self.cell_m)
        k2 = frequency[:, None] ** 2 + frequency[None, :] ** 2
        sigma = self.correlation_m
        smooth = np.fft.ifft2(np.fft.fft2(noise) * np.exp(-2 * (np.pi * sigma) ** 2 * k2)).real
        smooth -= smooth.mean()
        return smooth * (self.roughness_m / max(float(smooth.std()), 1e-12))

    def add_to(self, spec: mujoco.MjSpec, body: BodyShape) -> None:
        """The field (the snake's ground) and the floor plane moved out of reach below it."""
        heights = self.heights()
        low, high = float(heights.min()), float(heights.max())
        relief = max(high - low, _MIN_RELIEF_M)
        count = heights.shape[0]
        spec.add_hfield(
            name="rough",
            nrow=count,
            ncol=count,
            size=[self.size_m, self.size_m, relief, _BASE_M],
            userdata=((heights - low) / relief).ravel().tolist(),
        )
        spec.worldbody.add_geom(
            name="rough",
            type=mujoco.mjtGeom.mjGEOM_HFIELD,
            hfieldname="rough",
            pos=[0.0, 0.0, low],
            contype=GROUND_BITS,
            conaffinity=GROUND_BITS,
            rgba=[0.45, 0.42, 0.35, 1.0],
        )
        floor = spec.geom("floor")
        floor.pos = [0.0, 0.0, low - _BASE_M - 0.01]
        floor.contype = 0
        floor.conaffinity = 0

    def start_pose(self, body: BodyShape) -> StartPose:
        """Above the highest point under the body's start, so it settles onto the field."""
        heights = self.heights()
        centre = heights.shape[0] // 2
        reach = round((body.body_length_m + body.radius_m) / self.cell_m) + 1
        strip = round(2 * body.radius_m / self.cell_m) + 1
        under = heights[centre - strip : centre + strip + 1, centre - reach : centre + strip + 1]
        return StartPose((0.0, 0.0, float(under.max()) + body.radius_m + 1e-3))
