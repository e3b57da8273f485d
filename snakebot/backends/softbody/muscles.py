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
import numpy.typing as npt

from snakebot.backends.softbody.lattice import (
    CORNER_SIGNS,
    CORNERS,
    FloatArray,
    IntArray,
    Lattice,
    SpringKind,
)

AXES = ("yaw", "pitch", "axial")


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


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    """Row-wise dot product over the last axis."""
    out: FloatArray = np.einsum("...i,...i->...", a, b)
    return out


def _unit(a: FloatArray) -> FloatArray:
    out: FloatArray = a / np.sqrt(_dot(a, a))[..., None]
    return out


class MuscleMap:
    """Rest lengths from channel commands and channel values from point positions.

    ``segment_length_m`` (L0), ``width_m`` and ``height_m`` are the relaxed cube's sides. Every
    method also takes a leading batch shape (B, ...) on its arrays, computed in one pass.
    """

    def __init__(
        self, lattice: Lattice, segment_length_m: float, width_m: float, height_m: float
    ) -> None:
        self.lattice = lattice
        self.segment_length_m = segment_length_m
        corners = CORNER_SIGNS * np.array([width_m / 2, height_m / 2])  # (4, 2): y, z
        springs = lattice.springs
        self._ring_springs = np.flatnonzero(lattice.ring >= 0)
        self._ring_of = lattice.ring[self._ring_springs]
        a, b = springs[self._ring_springs, 0] % CORNERS, springs[self._ring_springs, 1] % CORNERS
        self._ring_base = np.linalg.norm(corners[b] - corners[a], axis=1)
        self._seg_springs = np.flatnonzero(lattice.segment >= 0)
        self._seg_of = lattice.segment[self._seg_springs]
        # segment_efforts sums each segment's springs as one block of a reshape.
        per_segment = np.bincount(self._seg_of, minlength=lattice.segments)
        if np.any(np.diff(self._seg_of) < 0) or np.any(per_segment != per_segment[0]):
            raise ValueError("segment springs must come in equal blocks, segment by segment")
        front, back = (
            springs[self._seg_springs, 0] % CORNERS,
            springs[self._seg_springs, 1] % CORNERS,
        )
        self._front_yz = corners[front]  # (Mseg, 2)
        self._back_yz = corners[back]
        self.longitudinal: IntArray = lattice.of_kind(SpringKind.LONGITUDINAL)

    # -- commands -> rest lengths ---------------------------------------------------------------
    def rest_lengths(
        self, yaw: FloatArray, pitch: FloatArray, axial: FloatArray, ring_scale: FloatArray
    ) -> FloatArray:
        """Rest length (..., M) in m of every spring, for channels (..., S) and ring scales
        (..., R)."""
        yaw, pitch, axial = np.asarray(yaw), np.asarray(pitch), np.asarray(axial)
        batch = np.broadcast_shapes(yaw.shape, pitch.shape, axial.shape)[:-1]
        out = np.empty((*batch, self.lattice.spring_count))
        scale = np.broadcast_to(ring_scale, (*batch, self.lattice.rings))
        out[..., self._ring_springs] = self._ring_base * scale[..., self._ring_of]
        seg = self._seg_of
        cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
        chy, shy = np.cos(0.5 * yaw), np.sin(0.5 * yaw)
        chp, shp = np.cos(0.5 * pitch), np.sin(0.5 * pitch)
        length = self.segment_length_m * (1.0 - axial)
        # Back ring centre: the half turn Rz(yaw/2) Ry(pitch/2) of (-length, 0, 0).
        centre = -length[..., None] * np.stack((chy * chp, shy * chp, -shp), axis=-1)
        # Columns 1 (left) and 2 (up) of Rz(yaw) Ry(pitch): where the back ring's y, z go.
        zero = np.zeros_like(cy)
        left = np.stack((-sy, cy, zero), axis=-1)
        up = np.stack((cy * sp, sy * sp, cp), axis=-1)
        front_scale = scale[..., :-1][..., seg, None]
        back_scale = scale[..., 1:][..., seg, None]
        back = centre[..., seg, :] + back_scale * (
            self._back_yz[:, 0, None] * left[..., seg, :]
            + self._back_yz[:, 1, None] * up[..., seg, :]
        )
        back[..., 1:] -= front_scale * self._front_yz
        out[..., self._seg_springs] = np.sqrt(_dot(back, back))
        return out

    def rest_lengths_and_jacobian(
        self, yaw: FloatArray, pitch: FloatArray, axial: FloatArray, ring_scale: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """Rest lengths (M,) as ``rest_lengths`` for one command (S,) each, and their analytic
        derivatives (3, M): rows yaw, pitch, axial, each spring against its own segment's
        channel (a spring depends on one segment's channels only; ring springs on none)."""
        out = np.empty(self.lattice.spring_count)
        out[self._ring_springs] = self._ring_base * ring_scale[self._ring_of]
        seg = self._seg_of
        cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
        chy, shy = np.cos(0.5 * yaw), np.sin(0.5 * yaw)
        chp, shp = np.cos(0.5 * pitch), np.sin(0.5 * pitch)
        length = self.segment_length_m * (1.0 - axial)
        zero = np.zeros_like(cy)
        half = np.stack((chy * chp, shy * chp, -shp), axis=-1)
        centre = -length[:, None] * half
        left = np.stack((-sy, cy, zero), axis=-1)
        up = np.stack((cy * sp, sy * sp, cp), axis=-1)
        # d/d(yaw, pitch, axial) of the centre, left and up columns: (3, S, 3) each.
        d_centre = np.stack(
            (
                -0.5 * length[:, None] * np.stack((-shy * chp, chy * chp, zero), axis=-1),
                -0.5 * length[:, None] * np.stack((-chy * shp, -shy * shp, -chp), axis=-1),
                self.segment_length_m * half,
            )
        )
        d_left = np.stack((np.stack((-cy, -sy, zero), axis=-1), 0.0 * left, 0.0 * left))
        d_up = np.stack(
            (
                np.stack((-sy * sp, cy * sp, zero), axis=-1),
                np.stack((cy * cp, sy * cp, -sp), axis=-1),
                0.0 * up,
            )
        )
        back_scale = ring_scale[1:][seg, None]
        by, bz = self._back_yz[:, 0, None], self._back_yz[:, 1, None]
        back = centre[seg] + back_scale * (by * left[seg] + bz * up[seg])
        back[:, 1:] -= ring_scale[:-1][seg, None] * self._front_yz
        d_back = d_centre[:, seg] + back_scale * (by * d_left[:, seg] + bz * d_up[:, seg])
        lengths = np.sqrt(_dot(back, back))
        out[self._seg_springs] = lengths
        jacobian = np.zeros((3, self.lattice.spring_count))
        jacobian[:, self._seg_springs] = np.einsum("qmi,mi->qm", d_back, back) / lengths
        return out, jacobian

    def jacobian(
        self, yaw: FloatArray, pitch: FloatArray, axial: FloatArray, ring_scale: FloatArray
    ) -> FloatArray:
        """d(rest length)/d(channel) (3, M) for one command (S,) each; see
        ``rest_lengths_and_jacobian``."""
        return self.rest_lengths_and_jacobian(yaw, pitch, axial, ring_scale)[1]

    def segment_efforts(self, jacobian: FloatArray, spring_force_n: FloatArray) -> FloatArray:
        """Generalised muscle force per segment and channel (3, S) from spring forces (M,) (N,
        positive = extending): yaw and pitch in N·m, axial in N·m per unit strain, so that
        effort · channel rate is the muscles' power in W."""
        weighted = jacobian[:, self._seg_springs] * spring_force_n[self._seg_springs]
        out: FloatArray = weighted.reshape(3, self.lattice.segments, -1).sum(axis=2)
        return out

    def power_rows(
        self, jacobian: FloatArray, layout: ChannelLayout
    ) -> tuple[npt.NDArray[np.int64], FloatArray, FloatArray]:
        """Per joint of ``layout``, the K springs of its segment (N, K) and weights on them
        (N, K) each that turn the springs' forces N into the joint's effort
        (``segment_efforts``, as ``read_state`` reports it) and the springs' rates of length
        m/s into the joint's channel rate: the least-squares channel rates whose rest-length
        changes ``jacobian``ᵀ·rate best match the springs' (a segment has more springs than
        channels). Effort times rate is the muscle's power at any instant, which the backend
        integrates every physics step."""
        segments = self.lattice.segments
        springs = self._seg_springs.reshape(segments, -1)  # (S, K)
        blocks = np.moveaxis(jacobian[:, springs], 0, -1)  # (S, K, 3)
        across = np.swapaxes(blocks, -1, -2)  # (S, 3, K)
        try:
            rates = np.linalg.solve(across @ blocks, across)
        except np.linalg.LinAlgError:  # a channel that moves no spring in some pose
            rates = np.linalg.pinv(blocks)
        joints = np.arange(layout.joint_count)
        segment = joints // len(layout.channels)
        axis = np.array([AXES.index(c) for c in layout.channels])[joints % len(layout.channels)]
        columns = springs[segment].astype(np.int64)  # (N, K)
        effort_rows: FloatArray = jacobian[axis[:, None], columns]
        rate_rows: FloatArray = rates[segment, axis]
        return columns, effort_rows, rate_rows

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
    def ring_axes(
        self, positions: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Ring centres, forward (towards the head), left and up unit vectors, each (..., R, 3),
        from point positions (..., P, 3); the three axes are orthonormal."""
        rings = positions.reshape(*positions.shape[:-2], -1, CORNERS, 3)
        c0, c1, c2, c3 = (rings[..., c, :] for c in range(CORNERS))
        centres = 0.25 * (c0 + c1 + c2 + c3)
        left = _unit(c0 + c3 - c1 - c2)
        forward = _unit(np.cross(left, c0 + c1 - c2 - c3))
        return centres, forward, left, np.cross(forward, left)

    def ring_frames(self, positions: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Ring centres (..., R, 3) and frames (..., R, 3, 3), columns forward, left, up."""
        centres, forward, left, up = self.ring_axes(positions)
        return centres, np.stack((forward, left, up), axis=-1)

    def measure(self, positions: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Measured (yaw, pitch, axial), each (..., S), of the lattice at positions (..., P, 3).

        The tail-side ring's forward axis seen in the head-side ring's frame gives yaw and pitch
        (the inverse of Rz(yaw) Ry(pitch)); the centres' distance gives the strain.
        """
        return self.channels_of(*self.ring_axes(positions))

    def channels_of(
        self, centres: FloatArray, forward: FloatArray, left: FloatArray, up: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``measure`` from ring axes already computed by ``ring_axes``."""
        ahead = forward[..., 1:, :]
        x = _dot(forward[..., :-1, :], ahead)
        y = _dot(left[..., :-1, :], ahead)
        z = _dot(up[..., :-1, :], ahead)
        gap = np.diff(centres, axis=-2)
        length = np.sqrt(_dot(gap, gap))
        return (
            np.arctan2(y, x),
            np.arctan2(-z, np.hypot(x, y)),
            1.0 - length / self.segment_length_m,
        )

    def segment_lengths(self, positions: FloatArray) -> FloatArray:
        """Distance (S,) in m between consecutive ring centres."""
        centres = positions.reshape(-1, CORNERS, 3).mean(axis=1)
        gap = np.diff(centres, axis=0)
        return np.sqrt(_dot(gap, gap))


def layout_for(channels: Sequence[str], segments: int) -> ChannelLayout:
    """A ChannelLayout; ValueError for unknown or repeated channels."""
    return ChannelLayout(tuple(channels), segments)
