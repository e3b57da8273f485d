"""Miller's lattice: rings of four point masses, springs on every cube edge and face diagonal.

Pure numpy, no MuJoCo: the MuJoCo builder, the muscles, the directional friction and the tests'
reference integrator all share these index arrays.

Layout. ``S`` segments (cubes) need ``R = S + 1`` rings, ring 0 at the head (x = 0) and ring ``S``
at the tail (x = -S * segment length). Each ring has four corners, counted looking from the tail
towards the head: 0 left-top (+y, +z), 1 right-top, 2 right-bottom, 3 left-bottom. Point ``p`` is
corner ``p % 4`` of ring ``p // 4``, so positions reshape to (R, 4, 3).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np
import numpy.typing as npt

IntArray = npt.NDArray[np.intp]
FloatArray = npt.NDArray[np.float64]

CORNERS = 4
# Corner (y, z) signs: left = +y, top = +z (see the module docstring).
CORNER_SIGNS = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])
# The four side faces of a segment as corner pairs: top, right, bottom, left.
_SIDE_FACES = ((0, 1), (1, 2), (2, 3), (3, 0))


class SpringKind(IntEnum):
    """Where a spring sits: what the muscles may change about it."""

    RING_EDGE = 0  # around the circumference, in one ring
    RING_DIAGONAL = 1  # across a ring (the cube's front/back face diagonals)
    LONGITUDINAL = 2  # a cube edge from one ring to the next (the muscles)
    SIDE_DIAGONAL = 3  # across a side face of a cube


@dataclass(frozen=True)
class Lattice:
    """Index arrays of an ``segments``-cube lattice; shapes are given per attribute.

    ``springs`` (M, 2) point indices (head-side point first for springs between rings), ``kind``
    (M,) SpringKind, ``segment`` (M,) the segment a spring belongs to (-1 for ring springs),
    ``ring`` (M,) the ring a ring spring lies in (-1 otherwise).
    """

    segments: int
    springs: IntArray
    kind: IntArray
    segment: IntArray
    ring: IntArray

    @property
    def rings(self) -> int:
        """R = segments + 1."""
        return self.segments + 1

    @property
    def points(self) -> int:
        """P = 4 R point masses."""
        return CORNERS * self.rings

    @property
    def spring_count(self) -> int:
        """M springs: 6 per ring plus 12 per segment."""
        return int(self.springs.shape[0])

    @property
    def point_ring(self) -> IntArray:
        """Ring of each point (P,)."""
        return np.repeat(np.arange(self.rings), CORNERS)

    def of_kind(self, kind: SpringKind) -> IntArray:
        """Indices of the springs of one kind, in construction order."""
        return np.flatnonzero(self.kind == kind)


def build_lattice(segments: int) -> Lattice:
    """The spring graph of ``segments`` cubes in a row (Miller 1988: edges and face diagonals).

    Per ring: 4 edges and 2 diagonals; per segment: 4 longitudinal edges (corner c of ring i to
    corner c of ring i+1) and 2 diagonals on each of the 4 side faces. Raises ValueError for
    fewer than one segment.
    """
    if segments < 1:
        raise ValueError(f"a lattice needs at least one segment, got {segments}")
    pairs: list[tuple[int, int]] = []
    kinds: list[int] = []
    seg: list[int] = []
    ring: list[int] = []

    def add(a: int, b: int, kind: SpringKind, segment: int, in_ring: int) -> None:
        pairs.append((a, b))
        kinds.append(kind)
        seg.append(segment)
        ring.append(in_ring)

    for r in range(segments + 1):
        base = CORNERS * r
        for c in range(CORNERS):
            add(base + c, base + (c + 1) % CORNERS, SpringKind.RING_EDGE, -1, r)
        add(base + 0, base + 2, SpringKind.RING_DIAGONAL, -1, r)
        add(base + 1, base + 3, SpringKind.RING_DIAGONAL, -1, r)
    for s in range(segments):
        front, back = CORNERS * s, CORNERS * (s + 1)
        for c in range(CORNERS):
            add(front + c, back + c, SpringKind.LONGITUDINAL, s, -1)
        for a, b in _SIDE_FACES:
            add(front + a, back + b, SpringKind.SIDE_DIAGONAL, s, -1)
            add(front + b, back + a, SpringKind.SIDE_DIAGONAL, s, -1)
    return Lattice(
        segments=segments,
        springs=np.array(pairs, dtype=np.intp),
        kind=np.array(kinds, dtype=np.intp),
        segment=np.array(seg, dtype=np.intp),
        ring=np.array(ring, dtype=np.intp),
    )


def rest_positions(
    segments: int, segment_length_m: float, width_m: float, height_m: float, lift_m: float
) -> FloatArray:
    """Point positions (P, 3) of the straight body at rest, head ring at x = 0, tail towards -x.

    ``lift_m`` is the height of the bottom corners (a point's radius puts it on the floor).
    """
    x = -segment_length_m * np.arange(segments + 1)
    corner = CORNER_SIGNS * np.array([width_m / 2, height_m / 2])
    out = np.empty((segments + 1, CORNERS, 3))
    out[:, :, 0] = x[:, None]
    out[:, :, 1] = corner[None, :, 0]
    out[:, :, 2] = corner[None, :, 1] + height_m / 2 + lift_m
    return out.reshape(-1, 3)


def spring_lengths(positions: FloatArray, springs: IntArray) -> FloatArray:
    """Length (M,) in m of each spring (M, 2) for point positions (P, 3)."""
    delta = positions[springs[:, 1]] - positions[springs[:, 0]]
    lengths: FloatArray = np.sqrt(np.einsum("ij,ij->i", delta, delta))
    return lengths
