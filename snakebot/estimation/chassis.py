"""The virtual chassis (Rollinson, Buchan & Choset 2012): a body frame from the snake's shape.

The head of a snake swings with every wave, so its frame is a poor frame to describe the whole
body in. The virtual chassis is the frame of the body's principal axes: its origin is the
centroid of all module centres (the centre of mass, for equal modules) and its axes are the
right singular vectors of the centred (M, 3) module positions, x along the body's greatest
extent, y the next, z = x × y. A gait seen in it barely moves: sidewinding travels along a fixed
direction of the chassis frame while the head turns back and forth.

An SVD leaves each axis's sign free, and the order of y and z too where their extents cross.
``VirtualChassis`` resolves both so the frame never flips between cycles:

- x points from the tail towards the head (the projection of head minus tail is positive);
- y and z are matched to the previous cycle's by the module coordinates they give (the (M,)
  projections of the modules on each axis): the pairing with the larger correlation keeps its
  place, and a negative correlation flips the axis. Comparing coordinates, not axis vectors,
  needs no common frame between cycles (the head, where FK places the modules, moves too);
- z is always x × y (a right-handed frame); where that contradicts z's own match, the axis whose
  extent is the smaller (the less certain) gives way.

A body with no extent across its axis (straight, or a plane with no thickness) leaves the
axes it cannot see to the last frame's, carried as the head's frame carries them: the straight
start pose takes y and z from the head (head up on flat ground).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from snakebot.estimation.kinematics import cross3

FloatArray = npt.NDArray[np.float64]

DEGENERATE_RATIO = 1e-6
"""An extent below this fraction of the body's extent along x counts as none (float noise)."""

MIN_EXTENT_M = 0.002
"""A cross extent (RMS) below this counts as none: encoder noise alone bends a straight
12-module chain by about 1 mm, which would set the axes at random."""


@dataclass(frozen=True)
class ChassisFrame:
    """The virtual chassis of one cycle, in the frame the module positions came in (the head's).

    ``origin_m`` (3,) the modules' centroid; ``rotation`` (3, 3) its axes as columns (x along
    the body towards the head, y, z = x × y); ``extent_m`` (3,) the RMS spread of the modules
    along each axis (singular values / sqrt(M)); ``positions_m`` (M, 3) the modules in the
    chassis frame.
    """

    origin_m: FloatArray
    rotation: FloatArray
    extent_m: FloatArray
    positions_m: FloatArray

    def to_chassis(self, points_m: npt.ArrayLike) -> FloatArray:
        """Points (..., 3) from the head's frame into the chassis frame."""
        out: FloatArray = (np.asarray(points_m, dtype=float) - self.origin_m) @ self.rotation
        return out


class VirtualChassis:
    """Tracks the virtual chassis cycle by cycle so its axes never flip (see the module doc).

    ``update(positions)`` takes the module centres (M, 3) in the head's frame (FK of the
    measured joints: ``ChainGeometry.module_centres``) and returns that cycle's ``ChassisFrame``;
    ``reset`` forgets the history (the next frame starts from the head's axes). A cross extent
    under ``min_extent_m`` (RMS, m) counts as none (a straight body, to the encoders' noise).
    """

    def __init__(self, min_extent_m: float = MIN_EXTENT_M) -> None:
        if not (min_extent_m >= 0 and np.isfinite(min_extent_m)):
            raise ValueError(f"min_extent_m must be >= 0, got {min_extent_m}")
        self.min_extent_m = float(min_extent_m)
        self._last: ChassisFrame | None = None

    @property
    def last(self) -> ChassisFrame | None:
        """The frame of the latest update, or None before the first."""
        return self._last

    def reset(self) -> None:
        """Forget the previous frame."""
        self._last = None

    def update(self, positions_m: npt.ArrayLike) -> ChassisFrame:
        """The chassis frame of module centres ``positions_m`` (M, 3), M >= 2, in the head's
        frame. ValueError for a wrong shape or non-finite positions."""
        points = np.asarray(positions_m, dtype=float)
        if points.ndim != 2 or points.shape[1] != 3 or points.shape[0] < 2:
            raise ValueError(f"expected (M, 3) module positions with M >= 2, got {points.shape}")
        if not np.all(np.isfinite(points)):
            raise ValueError("module positions must be finite")
        origin = points.mean(axis=0)
        centred = points - origin
        _, singular, vt = np.linalg.svd(centred, full_matrices=False)
        axes = vt.copy()  # rows: principal axes, largest extent first
        if axes.shape[0] < 3:  # two modules: one axis only
            axes = np.vstack([axes, np.zeros((3 - axes.shape[0], 3))])
            singular = np.concatenate([singular, np.zeros(3 - singular.size)])
        x = axes[0]
        if x @ (points[0] - points[-1]) < 0:
            x = -x
        floor = max(
            DEGENERATE_RATIO * max(float(singular[0]), 1e-12),
            self.min_extent_m * np.sqrt(points.shape[0]),
        )
        y, z = self._cross_axes(centred, x, axes[1], axes[2], singular, floor)
        rotation = np.column_stack([x, y, z])
        frame = ChassisFrame(
            origin_m=origin,
            rotation=rotation,
            extent_m=self._extent(centred, rotation),
            positions_m=centred @ rotation,
        )
        self._last = frame
        return frame

    @staticmethod
    def _extent(centred: FloatArray, rotation: FloatArray) -> FloatArray:
        spread: FloatArray = np.sqrt(np.mean((centred @ rotation) ** 2, axis=0))
        return spread

    def _cross_axes(
        self,
        centred: FloatArray,
        x: FloatArray,
        second: FloatArray,
        third: FloatArray,
        singular: FloatArray,
        floor: float,
    ) -> tuple[FloatArray, FloatArray]:
        """y and z for body axis ``x``, matched to the last frame (see the module doc)."""
        last = self._last
        if singular[1] <= floor:  # a line: nothing across it to see
            return self._carried_axes(x)
        candidates = (second, third)
        before: FloatArray | None = None
        if last is None or last.extent_m[1] <= floor / np.sqrt(centred.shape[0]):
            # First frame, or the last was a line: compare axis vectors with the head's own
            # y and z (or the last frame's, the head having barely moved in one cycle).
            reference = np.eye(3)[1:] if last is None else last.rotation[:, 1:].T
            scores = np.array([[c @ r for r in reference] for c in candidates])
        else:
            if last.positions_m.shape[0] != centred.shape[0]:
                raise ValueError("the module count changed between cycles")
            before = last.positions_m[:, 1:]  # (M, 2)
            scores = (centred @ np.column_stack(candidates)).T @ before  # mine i, last j
        if abs(scores[0, 0]) + abs(scores[1, 1]) >= abs(scores[0, 1]) + abs(scores[1, 0]):
            y_index = 0
        else:
            y_index = 1
        y_extent, z_extent = singular[1 + y_index], singular[2 - y_index]
        y = candidates[y_index] * (1.0 if scores[y_index, 0] >= 0 else -1.0)
        y = y - (y @ x) * x
        y /= math.sqrt(float(y @ y))
        z = cross3(x, y)
        if before is None:
            z_before = np.array([0.0, 0.0, 1.0]) if last is None else last.rotation[:, 2]
            z_score = float(z @ z_before)
        else:
            z_score = float((centred @ z) @ before[:, 1])
        if z_extent > floor and z_score < 0 and z_extent > y_extent:
            # z's own match says flip and z is the better seen axis: turn the pair about x.
            y, z = -y, -z
        return y, z

    def _carried_axes(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """y and z for a body that is a line along ``x``: the head's z (or the last frame's)
        made perpendicular to x."""
        last = self._last
        reference = np.array([0.0, 0.0, 1.0]) if last is None else last.rotation[:, 2]
        z = reference - (reference @ x) * x
        if np.linalg.norm(z) < 1e-9:  # the body points along the reference: use the head's y
            fallback = np.array([0.0, 1.0, 0.0])
            z = cross3(x, fallback - (fallback @ x) * x)
        z /= np.linalg.norm(z)
        return cross3(z, x), z
