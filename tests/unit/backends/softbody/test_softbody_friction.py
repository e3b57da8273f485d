from __future__ import annotations

import numpy as np
import pytest

from snakebot.backends.softbody.friction import (
    DirectionalFriction,
    remove_backward,
    spine_directions,
)
from snakebot.backends.softbody.lattice import rest_positions


def _paper_rule(velocity: np.ndarray, spine: np.ndarray) -> np.ndarray:
    """Miller's rule as the paper writes it, one point at a time."""
    out = velocity.copy()
    for p in range(len(out)):
        along = float(spine[p] @ out[p])
        if along < 0.0:
            out[p] = out[p] - spine[p] * along
    return out


def test_spine_points_to_the_head_with_central_differences() -> None:
    centres = np.array([[0.0, 0, 0], [-1, 0, 0], [-2, -1, 0], [-3, -1, 0]])
    spine = spine_directions(centres)
    np.testing.assert_allclose(spine[0], [1, 0, 0])  # one-sided at the head
    np.testing.assert_allclose(spine[1], np.array([2, 1, 0]) / np.sqrt(5))
    np.testing.assert_allclose(spine[3], [1, 0, 0])  # one-sided at the tail
    np.testing.assert_allclose(np.linalg.norm(spine, axis=1), 1.0)


def test_only_the_backward_component_goes() -> None:
    velocity = np.array([[-1.0, 0.5, 0.2], [2.0, -0.3, 0.0], [0.0, 1.0, 0.0]])
    spine = np.tile([1.0, 0.0, 0.0], (3, 1))
    projected = velocity.copy()
    assert remove_backward(projected, spine, np.arange(3)) == 1
    np.testing.assert_allclose(projected[0], [0.0, 0.5, 0.2])  # backward x removed, rest kept
    np.testing.assert_allclose(projected[1:], velocity[1:])  # forward and sideways untouched


def _friction(segments: int) -> tuple[DirectionalFriction, np.ndarray]:
    start = rest_positions(segments, 0.02, 0.02, 0.02, 0.003)
    points = len(start)
    # Geoms 0 (the floor) and 1..P (the points), as in a compiled body.
    return DirectionalFriction(np.arange(1, points + 1), points + 1, start), start


def test_the_vectorised_rule_equals_the_papers_loop_on_touching_points() -> None:
    rule, start = _friction(5)
    rng = np.random.default_rng(1)
    displacement = rng.normal(0, 0.003, start.shape)
    velocity = rng.normal(0, 0.1, start.shape)
    touching = np.arange(0, len(start), 2)  # every other point is on the floor
    contacts = np.stack([np.zeros_like(touching), touching + 1], axis=1)
    centres = (start + displacement).reshape(-1, 4, 3).mean(axis=1)
    spine = spine_directions(centres)[np.arange(len(start)) // 4]
    expected = velocity.copy()
    expected[touching] = _paper_rule(velocity[touching], spine[touching])
    backward = int((np.einsum("ij,ij->i", velocity, spine)[touching] < 0).sum())
    rule.apply(displacement, velocity, contacts)
    np.testing.assert_allclose(velocity, expected, atol=1e-15)
    assert rule.projected == backward > 0


def test_switched_off_or_without_contacts_nothing_changes() -> None:
    rule, start = _friction(3)
    velocity = -np.ones_like(start)
    before = velocity.copy()
    rule.apply(np.zeros_like(start), velocity, np.zeros((0, 2), dtype=np.intp))
    np.testing.assert_array_equal(velocity, before)
    rule.enabled = False
    rule.apply(np.zeros_like(start), velocity, np.array([[0, 1]]))
    np.testing.assert_array_equal(velocity, before)


@pytest.mark.parametrize("pairs", [[[0, 3]], [[3, 0]], [[3, 0], [0, 3], [5, 0]]])
def test_touching_reads_either_side_of_a_contact(pairs: list[list[int]]) -> None:
    rule, _ = _friction(2)
    touch = rule.touching(np.array(pairs))
    assert set(np.flatnonzero(touch)) == {geom - 1 for pair in pairs for geom in pair if geom}
