"""Muscles: the controller's joint targets become spring rest lengths, and the lattice's shape
becomes measured joint angles again.

Each segment takes three channels: ``yaw`` (rad, bend about the up axis: the left side
lengthens and the right shortens), ``pitch`` (rad, bend about the left axis: the bottom
lengthens and the top shortens) and ``axial`` (strain, 0.3 = 30 % shorter). Signs follow the
rigid twin: a positive yaw swings the tail-side ring to the right (-y), a positive pitch lifts it.

A command fixes a *target shape* for every segment: the tail-side ring turned by Rz(yaw)·Ry(pitch)
against the head-side ring, its centre at ``L0 (1 - axial)`` along the half-turned axis. Every
spring's rest length is its length in that shape, so the springs never fight one another and the
relaxed body takes exactly the commanded pose; ``measure`` inverts it from the ring frames. Miller's
volume preservation scales the rings' rest sizes by 1/sqrt(l / L0), l the segment's length.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from snakebot.backends.softbody.lattice import (
    CORNER_SIGNS,
    CORNERS,
    FloatArray,
    IntArray,
    Lattice,
    SpringKind,
)

AXES = ("yaw", "pitch", "axial")
_EPS = 1e-6


@dataclass(frozen=True)
class ChannelLayout:
    """Which joint index drives which channel: ``channels`` per segment, segment by segment.

    Joint ``j`` is channel ``channels[j % k]`` of segment ``j // k`` (k = len(channels)), so a
    ("yaw", "pitch") layout alternates yaw and pitch like a rigid yaw/pitch snake.
    """

    channels: tuple[str, ...]
    segments: int

    def __post_init__(self) -> None:
        if not self.channels or len(set(self.channels)) != len(self.channels):
            raise ValueError(f"channels must be distinct and non-empty, got {self.channels}")
        unknown = [c for c in self.channels if c not in AXES]
        if unknown:
            raise ValueError(f"unknown channel {unknown[0]!r}; expected one of {', '.join(AXES)}")

    @property
    def joint_count(self) -> int:
        """N = segments * len(channels)."""
        return self.segments * len(self.channels)

    def split(self, joints: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(yaw, pitch, axial), each (S,), from joint values (N,); absent channels are 0."""
        table = np.asarray(joints, dtype=float).reshape(self.segments, len(self.channels))
        zero = np.zeros(self.segments)
        out = [table[:, self.channels.index(a)] if a in self.channels else zero for a in AXES]
        return out[0], out[1], out[2]

    def join(self, yaw: FloatArray, pitch: FloatArray, axial: FloatArray) -> FloatArray:
        """Joint values (N,) from the channel arrays (S,) each."""
        by_axis = {"yaw": yaw, "pitch": pitch, "axial": axial}
        joined: FloatArray = np.stack([by_axis[c] for c in self.channels], axis=1).reshape(-1)
        return joined


def _rotations(yaw: FloatArray, pitch: FloatArray) -> FloatArray:
    """Rz(yaw) @ Ry(pitch) for each segment, shape (S, 3, 3)."""
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    out = np.empty((yaw.shape[0], 3, 3))
    out[:, 0, 0], out[:, 0, 1], out[:, 0, 2] = cy * cp, -sy, cy * sp
    out[:, 1, 0], out[:, 1, 1], out[:, 1, 2] = sy * cp, cy, sy * sp
    out[:, 2, 0], out[:, 2, 1], out[:, 2, 2] = -sp, 0.0, cp
    return out


class MuscleMap:
    """Rest lengths from channel commands and channel values from point positions.

    ``segment_length_m`` (L0), ``width_m`` and ``height_m`` are the relaxed cube's sides.
    """

    def __init__(
        self, lattice: Lattice, segment_length_m: float, width_m: float, height_m: float
    ) -> None:
        self.lattice = lattice
        self.segment_length_m = segment_length_m
        self.corners = np.zeros((CORNERS, 3))
        self.corners[:, 1:] = CORNER_SIGNS * np.array([width_m / 2, height_m / 2])
        springs = lattice.springs
        self._ring_springs = np.flatnonzero(lattice.ring >= 0)
        self._ring_of = lattice.ring[self._ring_springs]
        a, b = springs[self._ring_springs, 0] % CORNERS, springs[self._ring_springs, 1] % CORNERS
        self._ring_base = np.linalg.norm(self.corners[b] - self.corners[a], axis=1)
        self._seg_springs = np.flatnonzero(lattice.segment >= 0)
        self._seg_of = lattice.segment[self._seg_springs]
        self._front_corner = springs[self._seg_springs, 0] % CORNERS
        self._back_corner = springs[self._seg_springs, 1] % CORNERS
        self.longitudinal: IntArray = lattice.of_kind(SpringKind.LONGITUDINAL)

    # -- commands -> rest lengths ---------------------------------------------------------------
    def rest_lengths(
        self, yaw: FloatArray, pitch: FloatArray, axial: FloatArray, ring_scale: FloatArray
    ) -> FloatArray:
        """Rest length (M,) in m of every spring, for channels (S,) each and ring scales (R,)."""
        out = np.empty(self.lattice.spring_count)
        out[self._ring_springs] = self._ring_base * ring_scale[self._ring_of]
        rotation = _rotations(yaw, pitch)
        half = _rotations(0.5 * yaw, 0.5 * pitch)
        length = self.segment_length_m * (1.0 - axial)
        centre = -length[:, None] * half[:, :, 0]  # half-turn of (-L, 0, 0)
        front = self.corners[None] * ring_scale[:-1, None, None]
        back_local = self.corners[None] * ring_scale[1:, None, None]
        back = centre[:, None, :] + np.einsum("sij,scj->sci", rotation, back_local)
        seg = self._seg_of
        delta = back[seg, self._back_corner] - front[seg, self._front_corner]
        out[self._seg_springs] = np.sqrt(np.einsum("ij,ij->i", delta, delta))
        return out

    def jacobian(
        self, yaw: FloatArray, pitch: FloatArray, axial: FloatArray, ring_scale: FloatArray
    ) -> FloatArray:
        """d(rest length)/d(channel) (3, M): rows yaw, pitch, axial, each spring against its own
        segment's channel (a spring depends on one segment's channels only)."""
        base = self.rest_lengths(yaw, pitch, axial, ring_scale)
        rows = [
            self.rest_lengths(yaw + _EPS, pitch, axial, ring_scale),
            self.rest_lengths(yaw, pitch + _EPS, axial, ring_scale),
            self.rest_lengths(yaw, pitch, axial + _EPS, ring_scale),
        ]
        return (np.stack(rows) - base) / _EPS

    def segment_efforts(self, jacobian: FloatArray, spring_force_n: FloatArray) -> FloatArray:
        """Generalised muscle force per segment and channel (3, S) from spring forces (M,) (N,
        positive = extending): yaw and pitch in N·m, axial in N·m per unit strain, so that
        effort · channel rate is the muscles' power in W."""
        out = np.zeros((3, self.lattice.segments))
        weighted = jacobian[:, self._seg_springs] * spring_force_n[self._seg_springs]
        for row in range(3):
            np.add.at(out[row], self._seg_of, weighted[row])
        return out

    def ring_scale(self, segment_length_m: FloatArray) -> FloatArray:
        """Miller's volume preservation: ring size factor (R,) from segment lengths (S,) in m.

        A segment of length l keeps its volume with cross-section sides times 1/sqrt(l / L0); a
        ring between two segments takes the mean of their factors.
        """
        ratio = np.maximum(segment_length_m / self.segment_length_m, 0.05)
        factor = 1.0 / np.sqrt(ratio)
        rings = np.empty(factor.shape[0] + 1)
        rings[0], rings[-1] = factor[0], factor[-1]
        rings[1:-1] = 0.5 * (factor[:-1] + factor[1:])
        return rings

    # -- positions -> channels ----------------------------------------------------------------
    def ring_frames(self, positions: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Ring centres (R, 3) and frames (R, 3, 3) from point positions (P, 3).

        A frame's columns are forward (towards the head), left and up, orthonormal.
        """
        rings = positions.reshape(-1, CORNERS, 3)
        centres = rings.mean(axis=1)
        left = rings[:, (0, 3)].sum(axis=1) - rings[:, (1, 2)].sum(axis=1)
        up = rings[:, (0, 1)].sum(axis=1) - rings[:, (2, 3)].sum(axis=1)
        left /= np.linalg.norm(left, axis=1, keepdims=True)
        forward = np.cross(left, up)
        forward /= np.linalg.norm(forward, axis=1, keepdims=True)
        up = np.cross(forward, left)
        return centres, np.stack((forward, left, up), axis=2)

    def measure(self, positions: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Measured (yaw, pitch, axial), each (S,), of the lattice at positions (P, 3)."""
        centres, frames = self.ring_frames(positions)
        relative = np.einsum("sji,sjk->sik", frames[:-1], frames[1:])
        yaw = np.arctan2(relative[:, 1, 0], relative[:, 0, 0])
        pitch = np.arctan2(-relative[:, 2, 0], np.hypot(relative[:, 0, 0], relative[:, 1, 0]))
        length = np.linalg.norm(np.diff(centres, axis=0), axis=1)
        return yaw, pitch, 1.0 - length / self.segment_length_m

    def segment_lengths(self, positions: FloatArray) -> FloatArray:
        """Distance (S,) in m between consecutive ring centres."""
        centres = positions.reshape(-1, CORNERS, 3).mean(axis=1)
        lengths: FloatArray = np.linalg.norm(np.diff(centres, axis=0), axis=1)
        return lengths


def layout_for(channels: Sequence[str], segments: int) -> ChannelLayout:
    """A ChannelLayout; ValueError for unknown or repeated channels."""
    return ChannelLayout(tuple(channels), segments)
