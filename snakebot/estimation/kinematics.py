"""Forward kinematics of a servo chain from its measured joint angles, in numpy only.

The chain is the twin's (snakebot.backends.twin.model_builder): module 0 (the head) has its frame
at the origin facing +x; each next module's frame sits ``length_m`` behind (-x) its parent's and
turns about its joint's axis (yaw: z, pitch: y, in the child's frame) by the joint angle. A
module's centre (its centre of mass: a uniform capsule) is ``length_m / 2`` behind its frame.
No MuJoCo here: the estimator runs on the servo bus too.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from snakebot.config.schema import RobotConfig

FloatArray = npt.NDArray[np.float64]

_AXIS_INDEX = {"yaw": 2, "pitch": 1}


def cross3(a: FloatArray, b: FloatArray) -> FloatArray:
    """a × b for 3-vectors (np.cross costs ten times as much on one pair)."""
    a0, a1, a2 = float(a[0]), float(a[1]), float(a[2])
    b0, b1, b2 = float(b[0]), float(b[1]), float(b[2])
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


@dataclass(frozen=True)
class ChainGeometry:
    """What forward kinematics needs of a chain: ``length_m`` joint to joint and each joint's
    bending axis ("yaw" or "pitch"), head to tail; ``link_count`` = joints + 1. ValueError for
    a non-positive length or an unknown axis."""

    length_m: float
    axes: tuple[str, ...]

    def __post_init__(self) -> None:
        if not (self.length_m > 0 and np.isfinite(self.length_m)):
            raise ValueError(f"link length must be a positive number of m, got {self.length_m}")
        unknown = sorted(set(self.axes) - set(_AXIS_INDEX))
        if unknown:
            raise ValueError(f"joint axes must be yaw or pitch, got {unknown}")

    @functools.cached_property
    def _yaw_mask(self) -> npt.NDArray[np.bool_]:
        return np.array([axis == "yaw" for axis in self.axes], dtype=bool)

    @classmethod
    def of_robot(cls, robot: RobotConfig) -> ChainGeometry:
        """The geometry of ``robot``'s chain."""
        return cls(float(robot.link.length_m), tuple(j.axis for j in robot.joints))

    @property
    def joint_count(self) -> int:
        """N joints."""
        return len(self.axes)

    @property
    def link_count(self) -> int:
        """M = N + 1 modules."""
        return len(self.axes) + 1

    @property
    def planar(self) -> bool:
        """Every joint bends in yaw: the body stays in the head's x-y plane."""
        return all(axis == "yaw" for axis in self.axes)

    def frames(self, position_rad: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Every module's frame in the head's frame for joint angles (N,) rad: origins (M, 3) m
        and rotations (M, 3, 3) (columns: the module's x, y, z axes). ValueError for a wrong
        shape."""
        q = np.asarray(position_rad, dtype=float)
        if q.shape != (self.joint_count,):
            raise ValueError(f"expected ({self.joint_count},) joint angles, got shape {q.shape}")
        count = self.link_count
        cos, sin = np.cos(q), np.sin(q)
        turns = np.zeros((self.joint_count, 3, 3))  # each joint's turn, built at once
        yaw = self._yaw_mask
        pitch = ~yaw
        turns[yaw, 0, 0] = turns[yaw, 1, 1] = cos[yaw]  # about z: x -> (c, s, 0)
        turns[yaw, 0, 1], turns[yaw, 1, 0] = -sin[yaw], sin[yaw]
        turns[yaw, 2, 2] = 1.0
        turns[pitch, 0, 0] = turns[pitch, 2, 2] = cos[pitch]  # about y: x -> (c, 0, -s)
        turns[pitch, 0, 2], turns[pitch, 2, 0] = sin[pitch], -sin[pitch]
        turns[pitch, 1, 1] = 1.0
        rotations = np.empty((count, 3, 3))
        rotations[0] = np.eye(3)
        for i in range(self.joint_count):
            np.matmul(rotations[i], turns[i], out=rotations[i + 1])
        origins = np.zeros((count, 3))
        np.cumsum(-self.length_m * rotations[:-1, :, 0], axis=0, out=origins[1:])
        return origins, rotations

    def module_centres(self, position_rad: npt.ArrayLike) -> FloatArray:
        """Every module's centre (M, 3) m in the head's frame for joint angles (N,) rad."""
        origins, rotations = self.frames(position_rad)
        centres: FloatArray = origins - 0.5 * self.length_m * rotations[:, :, 0]
        return centres
