from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from snakebot.backends.chain.ticks import TickConverter
from snakebot.config import load_robot
from snakebot.config.schema import RobotConfig
from snakebot.servo import ticks

rad_to_ticks = functools.partial(ticks.rad_to_ticks, ticks=ticks.X_SERIES_TICKS)
ticks_to_rad = functools.partial(ticks.ticks_to_rad, ticks=ticks.X_SERIES_TICKS)

TICK = 2 * math.pi / 4096


def robot_with(offsets: list[float], directions: list[int]) -> RobotConfig:
    robot = load_robot("snake8")
    joints = tuple(
        dataclasses.replace(j, zero_offset_rad=o, direction=d)
        for j, o, d in zip(robot.joints, offsets, directions, strict=True)
    )
    return dataclasses.replace(robot, joints=joints)


def test_centre_quarter_turn_and_direction() -> None:
    assert rad_to_ticks(0.0) == 2048
    assert rad_to_ticks(math.pi / 2) == 3072
    assert rad_to_ticks(math.pi / 2, direction=-1) == 1024
    assert rad_to_ticks(-math.pi / 2) == 1024


def test_zero_offset_is_added_before_the_direction() -> None:
    # ticks = 2048 + direction * (angle + offset) * 4096 / 2pi
    assert rad_to_ticks(0.0, zero_offset_rad=0.1) == 2048 + round(0.1 / TICK)
    assert rad_to_ticks(0.0, zero_offset_rad=0.1, direction=-1) == 2048 - round(0.1 / TICK)
    assert ticks_to_rad(2048, zero_offset_rad=0.1) == pytest.approx(-0.1)
    assert ticks_to_rad(2048 + round(0.3 / TICK), zero_offset_rad=0.1) == pytest.approx(
        0.2, abs=TICK
    )


@given(
    angle=st.floats(-math.pi, math.pi),
    offset=st.floats(-0.5, 0.5),
    direction=st.sampled_from([1, -1]),
    model=st.sampled_from(
        [
            ticks.X_SERIES_TICKS,
            ticks.TickModel(count=1024, travel_deg=300.0, centre=512, maximum=1023),
            ticks.TickModel(count=1003846, centre=501923, maximum=1003845),
        ]
    ),
)
def test_round_trip_within_half_a_tick(
    angle: float, offset: float, direction: int, model: ticks.TickModel
) -> None:
    kw = {"zero_offset_rad": offset, "direction": direction}
    back = model.to_rad(model.to_ticks(angle, **kw), **kw)
    assert abs(back - angle) <= model.rad_per_tick / 2 + 1e-9


def test_vectorised_converter_matches_the_scalar_functions() -> None:
    offsets = [0.0, 0.1, -0.2, 0.05, 0.0, 0.3, -0.3, 0.01]
    directions = [1, -1, 1, -1, -1, 1, 1, -1]
    converter = TickConverter.for_robot(robot_with(offsets, directions))
    angles = np.linspace(-1.2, 1.2, 8)
    ticks = converter.to_ticks(angles)
    expected = [
        rad_to_ticks(a, zero_offset_rad=o, direction=d)
        for a, o, d in zip(angles, offsets, directions, strict=True)
    ]
    assert ticks.tolist() == expected
    assert ticks.dtype == np.int64
    np.testing.assert_allclose(converter.to_rad(ticks), angles, atol=TICK / 2 + 1e-12)


def test_goal_ticks_clip_and_refuse_non_finite_angles() -> None:
    converter = TickConverter.for_robot(robot_with([0.0] * 8, [1, -1] * 4))
    ticks, clipped = converter.goal_ticks(np.full(8, 0.5))
    assert not clipped
    assert ticks == converter.to_ticks(np.full(8, 0.5)).tolist()
    ticks, clipped = converter.goal_ticks(np.full(8, 2.0))
    assert clipped
    assert ticks == converter.clip_ticks(converter.to_ticks(np.full(8, 2.0))).tolist()
    low, high = converter.lower_ticks.tolist(), converter.upper_ticks.tolist()
    # below the lower joint limit: the low tick end, or the high one on a reversed joint
    assert converter.goal_ticks([-2.0] * 8)[0] == [low[0], high[1]] * 4
    for bad in (np.nan, np.inf):
        angles = np.zeros(8)
        angles[3] = bad
        with pytest.raises(ValueError, match="non-finite"):
            converter.goal_ticks(angles)


@given(
    offset=st.floats(-0.4, 0.4),
    direction=st.sampled_from([1, -1]),
    angles=st.lists(st.floats(-3.0, 3.0), min_size=8, max_size=8),
)
def test_clipped_goals_stay_inside_the_joint_limits(
    offset: float, direction: int, angles: list[float]
) -> None:
    converter = TickConverter.for_robot(robot_with([offset] * 8, [direction] * 8))
    assert np.all(converter.lower_ticks <= converter.upper_ticks)
    clipped = converter.clip_ticks(converter.to_ticks(np.array(angles)))
    back = converter.to_rad(clipped)
    assert np.all(back >= converter.lower_rad - 1e-9)
    assert np.all(back <= converter.upper_rad + 1e-9)


def test_limits_in_ticks_for_a_reversed_offset_joint() -> None:
    converter = TickConverter.for_robot(robot_with([0.1] * 8, [-1] * 8))
    # joint range -1.5..1.5 rad, offset 0.1, reversed: ticks 2048 - (angle + 0.1) / TICK
    assert converter.lower_ticks[0] == math.ceil(2048 - 1.6 / TICK)
    assert converter.upper_ticks[0] == math.floor(2048 + 1.4 / TICK)
    inside = converter.to_ticks(np.full(8, 0.5))
    np.testing.assert_array_equal(converter.clip_ticks(inside), inside)
