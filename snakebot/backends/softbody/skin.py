"""A smooth skin over the lattice, as Miller rendered his worms with bicubic patches.

Every skin vertex is a fixed blend of point masses: uniform cubic B-spline weights around each
ring (periodic over its four corners) times clamped cubic B-spline weights along the body, so
the skin is the B-spline surface whose control net is the lattice. MuJoCo's skin moves each
vertex by its bones' displacements; with weights summing to one and points that never rotate
(slide joints), a vertex stays exactly on the B-spline surface of the current lattice. Caps close
the head and the tail.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from snakebot.backends.softbody.lattice import CORNERS, FloatArray, IntArray

_AROUND = 16  # skin vertices around the body
_ALONG = 4  # skin rows per segment
_CAP_REACH = 0.4  # caps bulge this fraction of a segment beyond the end rings
_CAP_ANGLES = (0.45, 0.9, 1.25)  # rad: cap rings on a quarter-circle profile


def _cubic_basis(t: float) -> FloatArray:
    """Uniform cubic B-spline weights (4,) of control points i-1, i, i+1, i+2 at t in [0, 1)."""
    return (
        np.array([(1 - t) ** 3, 3 * t**3 - 6 * t**2 + 4, -3 * t**3 + 3 * t**2 + 3 * t + 1, t**3])
        / 6.0
    )


def _along_weights(rings: int, rows_per_segment: int) -> FloatArray:
    """Weights (rows, rings) of the rings for each skin row, clamped so the ends are the end
    rings (the end control points are tripled)."""
    padded = np.concatenate(([0, 0], np.arange(rings), [rings - 1, rings - 1]))
    spans = rings + 1  # knot spans between the padded control points that the curve covers
    rows = spans * rows_per_segment + 1
    out = np.zeros((rows, rings))
    for row in range(rows):
        u = row / rows_per_segment
        span = min(int(u), spans - 1)
        weights = _cubic_basis(u - span)
        for offset in range(4):
            out[row, padded[span + offset]] += weights[offset]
    return out


def _around_weights(count: int) -> FloatArray:
    """Weights (count, 4) of the four ring corners for each vertex around a ring (periodic)."""
    out = np.zeros((count, CORNERS))
    for k in range(count):
        u = CORNERS * k / count
        span = int(u)
        weights = _cubic_basis(u - span)
        for offset in range(4):
            out[k, (span - 1 + offset) % CORNERS] += weights[offset]
    return out


@dataclass(frozen=True)
class SkinMesh:
    """Vertex weights (V, P) over the points and triangles (F, 3), outward facing."""

    weights: FloatArray
    faces: IntArray


def skin_mesh(rings: int, rest: FloatArray) -> SkinMesh:
    """The skin of a lattice with ``rings`` rings whose rest positions are ``rest`` (P, 3)."""
    along = _along_weights(rings, _ALONG)
    around = _around_weights(_AROUND)
    points = rings * CORNERS
    # Tube vertex (row, k) = sum over ring r and corner c of along[row, r] * around[k, c].
    tube = np.einsum("ar,kc->akrc", along, around).reshape(-1, _AROUND, points)
    centre = np.zeros((rings, points))
    for r in range(rings):
        centre[r, CORNERS * r : CORNERS * (r + 1)] = 1.0 / CORNERS
    head_axis, tail_axis = centre[0] - centre[1], centre[-1] - centre[-2]
    # Round caps: rings shrinking towards a tip _CAP_REACH segments beyond the end ring.
    head_rings = [_cap_ring(tube[0], centre[0], head_axis, angle) for angle in _CAP_ANGLES]
    tail_rings = [_cap_ring(tube[-1], centre[-1], tail_axis, angle) for angle in _CAP_ANGLES]
    strips = [*reversed(head_rings), *tube, *tail_rings]
    tips = (centre[0] + _CAP_REACH * head_axis, centre[-1] + _CAP_REACH * tail_axis)
    weights = np.vstack([*strips, tips[0], tips[1]])
    count = len(strips)
    faces = []
    for strip in range(count - 1):
        for k in range(_AROUND):
            a, b = strip * _AROUND + k, strip * _AROUND + (k + 1) % _AROUND
            c, d = a + _AROUND, b + _AROUND
            faces += [(a, b, c), (b, d, c)]
    head_tip, tail_tip = count * _AROUND, count * _AROUND + 1
    last = (count - 1) * _AROUND
    for k in range(_AROUND):
        faces.append((head_tip, (k + 1) % _AROUND, k))
        faces.append((last + k, last + (k + 1) % _AROUND, tail_tip))
    mesh = SkinMesh(weights, np.array(faces, dtype=np.intp))
    return _outward(mesh, weights @ rest)


def _cap_ring(edge: FloatArray, centre: FloatArray, axis: FloatArray, angle: float) -> FloatArray:
    """Weights (AROUND, P) of a cap ring at ``angle`` rad over the end: a quarter-circle profile
    from the end ring ``edge`` (AROUND, P) towards the tip along ``axis`` (P,) weights."""
    radial, reach = np.cos(angle), np.sin(angle) * _CAP_REACH
    ring: FloatArray = radial * edge + (1.0 - radial) * centre + reach * axis
    return ring


def _outward(mesh: SkinMesh, vertices: FloatArray) -> SkinMesh:
    """Flip the winding if the triangles face inwards (their normals point to the axis)."""
    tri = vertices[mesh.faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    outward = tri.mean(axis=1) - vertices.mean(axis=0)
    outward[:, 0] = 0.0  # radial direction of the tube part; caps are few and agree in sign
    if float(np.einsum("ij,ij->", normals, outward)) < 0:
        return SkinMesh(mesh.weights, mesh.faces[:, ::-1].copy())
    return mesh


def add_skin(
    spec: mujoco.MjSpec,
    point_names: list[str],
    rest: FloatArray,
    *,
    inflate_m: float,
    rgba: tuple[float, float, float, float] = (0.78, 0.5, 0.48, 1.0),
) -> SkinMesh:
    """Add the skin over points ``point_names`` (P,) at rest positions ``rest`` (P, 3) to
    ``spec``, pushed out by ``inflate_m`` along its normals (the points' contact radius)."""
    rings = len(point_names) // CORNERS
    mesh = skin_mesh(rings, rest)
    skin = spec.add_skin(name="skin")
    skin.vert = (mesh.weights @ rest).reshape(-1).tolist()
    skin.face = mesh.faces.reshape(-1).tolist()
    skin.inflate = inflate_m
    skin.rgba = list(rgba)
    skin.bodyname = list(point_names)
    skin.bindpos = rest.reshape(-1).tolist()
    skin.bindquat = np.tile([1.0, 0.0, 0.0, 0.0], len(point_names)).tolist()
    ids, weights = [], []
    for bone in range(len(point_names)):
        used = np.flatnonzero(np.abs(mesh.weights[:, bone]) > 1e-12)
        ids.append(used.tolist())
        weights.append(mesh.weights[used, bone].tolist())
    skin.vertid = ids
    skin.vertweight = weights
    return mesh
