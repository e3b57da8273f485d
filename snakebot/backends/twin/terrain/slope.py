"""An incline: the floor plane tilted, the snake lying on it.

A tilted plane keeps MuJoCo's capsule-plane collider, so capsule pairs stay body-aligned
(learning-softbody-terrain.md §3.1); gravity stays vertical, so what is measured is in the world.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from snakebot.backends.twin.terrain.base import BodyShape, StartPose, Terrain, quat_about
from snakebot.backends.twin.terrain.params import param


@dataclass(frozen=True)
class Slope(Terrain):
    """The floor tilted by ``angle_deg``, rising towards ``direction_deg`` (0 = the head's +x)."""

    name = "slope"
    summary = "an incline (Marvi et al. 2014 climb up to ~20 deg)"

    angle_deg: float = param(10.0, 0.0, 45.0, "deg", "incline")
    direction_deg: float = param(0.0, -180.0, 180.0, "deg", "uphill direction, 0 = head ahead")

    def _rotation(self) -> list[float]:
        direction = math.radians(self.direction_deg)
        axis = (math.sin(direction), -math.cos(direction), 0.0)
        return quat_about(axis, math.radians(self.angle_deg))

    def add_to(self, spec: mujoco.MjSpec, body: BodyShape) -> None:
        """Tilt the scene's floor about the origin."""
        spec.geom("floor").quat = self._rotation()

    def start_pose(self, body: BodyShape) -> StartPose:
        """Lying on the incline, head at the origin, the body tilted with the floor."""
        quat = np.array(self._rotation())
        pos = np.zeros(3)
        mujoco.mju_rotVecQuat(pos, np.array([0.0, 0.0, body.radius_m + 1e-3]), quat)
        return StartPose(
            (float(pos[0]), float(pos[1]), float(pos[2])),
            (float(quat[0]), float(quat[1]), float(quat[2]), float(quat[3])),
        )
