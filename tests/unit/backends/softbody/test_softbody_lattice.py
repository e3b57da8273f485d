from __future__ import annotations

import itertools

import numpy as np
import pytest

from snakebot.backends.softbody.lattice import (
    SpringKind,
    build_lattice,
    rest_positions,
    spring_lengths,
)


@pytest.mark.parametrize("segments", [1, 6, 10])
def test_counts_follow_the_cube_chain(segments: int) -> None:
    lattice = build_lattice(segments)
    assert lattice.points == 4 * (segments + 1)
    assert lattice.spring_count == 6 * (segments + 1) + 12 * segments
    assert len(lattice.of_kind(SpringKind.LONGITUDINAL)) == 4 * segments
    assert len(lattice.of_kind(SpringKind.SIDE_DIAGONAL)) == 8 * segments


def test_six_segments_have_the_prototypes_114_springs() -> None:
    assert build_lattice(6).spring_count == 114


def test_every_cube_edge_and_face_diagonal_is_a_spring_once() -> None:
    side = 0.02
    lattice = build_lattice(3)
    positions = rest_positions(3, side, side, side, 0.0)
    pairs = {tuple(sorted(map(int, pair))) for pair in lattice.springs}
    assert len(pairs) == lattice.spring_count  # no spring twice
    # Within each cube the pairs at distance side (edges) or side*sqrt(2) (face diagonals), and
    # no body diagonals (side*sqrt(3)): exactly Miller's springs.
    for segment in range(3):
        corners = range(4 * segment, 4 * segment + 8)
        for a, b in itertools.combinations(corners, 2):
            distance = float(np.linalg.norm(positions[a] - positions[b]))
            expected = np.isclose(distance, side) or np.isclose(distance, side * np.sqrt(2))
            assert ((a, b) in pairs) == expected, (a, b, distance)


def test_rest_positions_put_the_head_at_x0_and_the_bottom_on_the_lift() -> None:
    positions = rest_positions(4, 0.03, 0.02, 0.01, 0.003).reshape(5, 4, 3)
    np.testing.assert_allclose(positions[0, :, 0], 0.0)
    np.testing.assert_allclose(positions[-1, :, 0], -0.12)
    assert positions[..., 2].min() == pytest.approx(0.003)
    assert positions[..., 2].max() == pytest.approx(0.013)
    # corner 0 is left-top, 1 right-top, 2 right-bottom, 3 left-bottom
    assert positions[0, 0, 1] > 0 and positions[0, 1, 1] < 0
    assert positions[0, 0, 2] > positions[0, 3, 2]


def test_spring_lengths_of_the_rest_shape() -> None:
    lattice = build_lattice(2)
    lengths = spring_lengths(rest_positions(2, 0.02, 0.02, 0.02, 0.0), lattice.springs)
    longitudinal = lengths[lattice.of_kind(SpringKind.LONGITUDINAL)]
    np.testing.assert_allclose(longitudinal, 0.02)
    np.testing.assert_allclose(lengths[lattice.of_kind(SpringKind.RING_DIAGONAL)], 0.02 * 2**0.5)


def test_no_segments_is_refused() -> None:
    with pytest.raises(ValueError, match="at least one segment"):
        build_lattice(0)
