from __future__ import annotations

import numpy as np
import pytest

from snakebot.backends.softbody.lattice import (
    SpringKind,
    build_lattice,
    rest_positions,
    spring_lengths,
)
from snakebot.backends.softbody.muscles import ChannelLayout, MuscleMap

SIDE = 0.02


def _map(segments: int) -> MuscleMap:
    return MuscleMap(build_lattice(segments), SIDE, SIDE, SIDE)


def _rz_ry(yaw: float, pitch: float) -> np.ndarray:
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    return rz @ ry


def _posed(yaw: np.ndarray, pitch: np.ndarray, axial: np.ndarray) -> np.ndarray:
    """Chain the segments' target shapes into world positions (P, 3), head ring at the origin."""
    corners = np.array([[0, 1, 1], [0, -1, 1], [0, -1, -1], [0, 1, -1]]) * SIDE / 2
    frame, centre = np.eye(3), np.zeros(3)
    rings = [centre + corners @ frame.T]
    for y, p, a in zip(yaw, pitch, axial, strict=True):
        centre = centre + frame @ _rz_ry(y / 2, p / 2) @ np.array([-SIDE * (1 - a), 0, 0])
        frame = frame @ _rz_ry(y, p)
        rings.append(centre + corners @ frame.T)
    return np.concatenate(rings)


def test_zero_command_gives_the_rest_shape_lengths() -> None:
    muscles = _map(5)
    zero = np.zeros(5)
    rest = spring_lengths(rest_positions(5, SIDE, SIDE, SIDE, 0.0), muscles.lattice.springs)
    np.testing.assert_allclose(muscles.rest_lengths(zero, zero, zero, np.ones(6)), rest)


def test_rest_lengths_are_the_lengths_of_one_consistent_pose() -> None:
    # Springs never fight: every rest length is the spring's length in the chained target pose.
    rng = np.random.default_rng(3)
    yaw, pitch, axial = rng.uniform(-0.5, 0.5, (3, 6))
    muscles = _map(6)
    rest = muscles.rest_lengths(yaw, pitch, 0.6 * axial, np.ones(7))
    pose = _posed(yaw, pitch, 0.6 * axial)
    np.testing.assert_allclose(rest, spring_lengths(pose, muscles.lattice.springs), atol=1e-12)


def test_measure_inverts_the_pose() -> None:
    rng = np.random.default_rng(4)
    yaw, pitch, axial = rng.uniform(-0.5, 0.5, (3, 6))
    measured = _map(6).measure(_posed(yaw, pitch, 0.6 * axial) + np.array([1.0, -2.0, 0.5]))
    np.testing.assert_allclose(measured[0], yaw, atol=1e-12)
    np.testing.assert_allclose(measured[1], pitch, atol=1e-12)
    np.testing.assert_allclose(measured[2], 0.6 * axial, atol=1e-12)


def test_signs_follow_the_rigid_twin() -> None:
    muscles = _map(1)
    lattice = muscles.lattice
    long = lattice.of_kind(SpringKind.LONGITUDINAL)  # corners 0 LT, 1 RT, 2 RB, 3 LB
    zero, one = np.zeros(1), np.ones(2)
    yawed = muscles.rest_lengths(np.array([0.3]), zero, zero, one)[long]
    assert yawed[0] > SIDE > yawed[1] and yawed[3] > SIDE > yawed[2]  # left lengthens
    pitched = muscles.rest_lengths(zero, np.array([0.3]), zero, one)[long]
    assert pitched[2] > SIDE > pitched[1]  # bottom lengthens, the top shortens
    shortened = muscles.rest_lengths(zero, zero, np.array([0.3]), one)[long]
    np.testing.assert_allclose(shortened, 0.7 * SIDE)
    # A positive yaw swings the tail to the right (-y), a positive pitch lifts it, as a hinge.
    assert _posed(np.array([0.3]), zero, zero)[4:].mean(axis=0)[1] < 0
    assert _posed(zero, np.array([0.3]), zero)[4:].mean(axis=0)[2] > 0


def test_volume_preservation_scales_rings_by_inverse_sqrt_of_length() -> None:
    muscles = _map(3)
    scale = muscles.ring_scale(np.array([0.5, 1.0, 2.0]) * SIDE)
    np.testing.assert_allclose(scale, [2**0.5, (2**0.5 + 1) / 2, (1 + 0.5**0.5) / 2, 0.5**0.5])
    # Section area times length is constant for a segment whose two rings share its factor.
    factor = muscles.ring_scale(np.array([0.64 * SIDE]))[0]
    assert factor**2 * 0.64 == pytest.approx(1.0)
    one = _map(1)
    zero = np.zeros(1)
    rest = one.rest_lengths(zero, zero, zero, np.array([factor, factor]))
    edges = rest[one.lattice.of_kind(SpringKind.RING_EDGE)]
    np.testing.assert_allclose(edges, SIDE * factor)


def test_jacobian_matches_finite_differences_per_segment() -> None:
    muscles = _map(4)
    rng = np.random.default_rng(5)
    yaw, pitch, axial = rng.uniform(-0.3, 0.3, (3, 4))
    scale = np.ones(5)
    jacobian = muscles.jacobian(yaw, pitch, axial, scale)
    step = np.zeros(4)
    step[2] = 1e-5
    moved = muscles.rest_lengths(yaw, pitch + step, axial, scale)
    expected = (moved - muscles.rest_lengths(yaw, pitch, axial, scale)) / 1e-5
    in_segment = muscles.lattice.segment == 2
    np.testing.assert_allclose(jacobian[1, in_segment], expected[in_segment], atol=1e-3)
    np.testing.assert_allclose(expected[~in_segment], 0.0, atol=1e-9)


def test_efforts_are_the_power_conjugates_of_the_channels() -> None:
    muscles = _map(3)
    rng = np.random.default_rng(6)
    yaw, pitch, axial = rng.uniform(-0.3, 0.3, (3, 3))
    scale = np.ones(4)
    jacobian = muscles.jacobian(yaw, pitch, axial, scale)
    force = rng.normal(size=muscles.lattice.spring_count)
    rate = rng.normal(size=(3, 3))
    efforts = muscles.segment_efforts(jacobian, force)
    # Muscle power: sum of force times spring-length rate, when lengths follow the channels.
    length_rate = (jacobian * rate[:, muscles.lattice.segment]).sum(axis=0)
    seg = muscles.lattice.segment >= 0
    assert float((efforts * rate).sum()) == pytest.approx(float((force * length_rate)[seg].sum()))


def test_layout_splits_and_joins_channels_segment_by_segment() -> None:
    layout = ChannelLayout(("pitch", "axial"), 3)
    assert layout.joint_count == 6
    joints = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0])
    yaw, pitch, axial = layout.split(joints)
    np.testing.assert_array_equal(yaw, 0.0)
    np.testing.assert_array_equal(pitch, [1.0, 3.0, 5.0])
    np.testing.assert_array_equal(axial, [2.0, 4.0, 6.0])
    np.testing.assert_array_equal(layout.join(yaw, pitch, axial), joints)
    with pytest.raises(ValueError, match="unknown channel 'roll'"):
        ChannelLayout(("yaw", "roll"), 2)
    with pytest.raises(ValueError, match="distinct"):
        ChannelLayout(("yaw", "yaw"), 2)
