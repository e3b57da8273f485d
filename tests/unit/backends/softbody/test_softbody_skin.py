from __future__ import annotations

import numpy as np

from snakebot.backends.softbody.lattice import rest_positions
from snakebot.backends.softbody.skin import skin_mesh


def test_every_vertex_is_an_affine_blend_of_points() -> None:
    mesh = skin_mesh(7, rest_positions(6, 0.02, 0.02, 0.02, 0.003))
    np.testing.assert_allclose(mesh.weights.sum(axis=1), 1.0)
    assert mesh.faces.min() == 0 and mesh.faces.max() == mesh.weights.shape[0] - 1


def test_the_skin_is_a_closed_rounded_tube_inside_the_lattice_facing_out() -> None:
    rest = rest_positions(6, 0.02, 0.02, 0.02, 0.003)
    mesh = skin_mesh(7, rest)
    vertices = mesh.weights @ rest
    centre_yz = rest[:, 1:].mean(axis=0)
    rings = np.linalg.norm(vertices[:-2, 1:] - centre_yz, axis=1).reshape(-1, 16)
    tube = rings[3:-3]  # three cap rings at each end, head then tail
    assert tube.max() <= 0.01 * np.sqrt(2) + 1e-12  # B-spline hull: within the square
    assert tube.min() > 0.009 and tube.max() - tube.min() < 0.001  # round, not a square
    assert rings[0].max() < 0.5 * tube.min() and rings[-1].max() < 0.5 * tube.min()  # caps
    # Closed: every edge is shared by exactly two triangles.
    edges = np.sort(mesh.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert set(counts) == {2}
    # Facing out: the signed volume of the closed mesh is positive.
    tri = vertices[mesh.faces]
    volume = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6
    assert volume > 0.5 * 0.12 * 0.02 * 0.02
