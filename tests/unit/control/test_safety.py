from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from snakebot.config import load_robot
from snakebot.control.cycle import CycleSchedule
from snakebot.control.safety import SafetyLayer, smooth_ramp
from snakebot.errors import SafetyLimitError

N = 6
LOWER = np.array([-1.5, -1.0, -0.5, -1.5, -0.2, -1.0])
UPPER = np.array([1.5, 1.0, 0.5, 0.3, 0.2, 1.2])
VMAX = 5.0

finite = st.floats(-1e6, 1e6, allow_nan=False)


@settings(max_examples=300, deadline=None)
@given(
    targets=st.lists(arrays(float, N, elements=finite), min_size=1, max_size=20),
    start=arrays(float, N, elements=st.floats(-3, 3)),
    dt=st.floats(1e-4, 0.05),
    amplitude=st.floats(0, 1),
)
def test_no_command_leaves_limits_or_speed(
    targets: list[np.ndarray], start: np.ndarray, dt: float, amplitude: float
) -> None:
    layer = SafetyLayer(LOWER, UPPER, VMAX, ramp_s=1.0)
    layer.reset(start)
    previous = start  # a joint may start outside its limits: it comes in, never goes further out
    for target in targets:
        command = layer.filter(target, dt, amplitude)
        assert np.all(command >= np.minimum(LOWER, previous) - 1e-12)
        assert np.all(command <= np.maximum(UPPER, previous) + 1e-12)
        assert np.all(np.abs(command - previous) <= VMAX * dt + 1e-9)
        previous = command


def test_in_range_target_passes_unchanged_when_slow() -> None:
    layer = SafetyLayer(LOWER, UPPER, VMAX, ramp_s=1.0)
    layer.reset(np.zeros(N))
    target = np.full(N, 0.01)
    np.testing.assert_allclose(layer.filter(target, 0.01), target)


def test_amplitude_ramps_towards_rest_pose() -> None:
    layer = SafetyLayer(LOWER, UPPER, VMAX, ramp_s=2.0)
    schedule = CycleSchedule(100.0, 10.0, layer.ramp_s)
    assert schedule.ramp_in(0.0) == 0.0
    assert schedule.ramp_in(1.0) == pytest.approx(0.5)
    assert schedule.ramp_in(2.5) == 1.0
    layer.reset(np.zeros(N))
    np.testing.assert_allclose(layer.filter(np.full(N, 0.1), 0.01, amplitude=0.5), 0.05)
    assert smooth_ramp(0.25) < 0.25  # gentle start


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_gait_output_stops_the_run(bad: float) -> None:
    layer = SafetyLayer(LOWER, UPPER, VMAX, ramp_s=1.0)
    target = np.zeros(N)
    target[3] = bad
    with pytest.raises(SafetyLimitError, match=r"joints \[3\]"):
        layer.filter(target, 0.01)


def test_speed_limit_comes_from_the_servo() -> None:
    robot = load_robot("snake8")
    layer = SafetyLayer.for_robot(robot)
    # 0.9 of the XL430-W250's 57 rpm no-load speed
    assert layer.max_speed_rad_s == pytest.approx(0.9 * 57 * 2 * np.pi / 60, rel=1e-3)


def test_a_joint_found_outside_its_limits_comes_in_at_the_slew_limit() -> None:
    layer = SafetyLayer(LOWER, UPPER, VMAX, ramp_s=1.0)
    start = np.zeros(N)
    start[0] = 2.5  # limit 1.5
    layer.reset(start)
    dt = 0.01
    path = [layer.filter(np.zeros(N), dt, amplitude=0.0)[0] for _ in range(60)]
    assert path[0] == pytest.approx(2.5 - VMAX * dt)  # the first command is one step, not 1 rad
    steps = np.diff([2.5, *path])
    assert np.all(steps <= 0) and np.all(steps >= -VMAX * dt - 1e-12)
    assert path[-1] == pytest.approx(0.0)


def test_a_clip_only_layer_sends_a_step_as_it_is_and_only_clips_to_the_limits() -> None:
    robot = load_robot("snake12")
    layer = SafetyLayer.clip_only(robot)
    layer.reset(np.zeros(12))
    step = np.zeros(12)
    step[3] = 0.7  # far beyond one cycle of the servo's speed: the step test's whole point
    assert robot.max_speed_rad_s * 0.01 < 0.7
    np.testing.assert_array_equal(layer.filter(step, 0.01), step)
    beyond = np.full(12, 10.0)
    np.testing.assert_array_equal(layer.filter(beyond, 0.01), robot.upper_rad)
    with pytest.raises(SafetyLimitError, match="non-finite"):
        layer.filter(np.full(12, np.nan), 0.01)
    # The robot's own layer holds the same step back to the servo's speed.
    limited = SafetyLayer.for_robot(robot)
    limited.reset(np.zeros(12))
    assert limited.filter(step, 0.01)[3] == pytest.approx(robot.max_speed_rad_s * 0.01)


def reference_filter(
    last: np.ndarray | None, target: np.ndarray, rest: np.ndarray, dt: float, amplitude: float
) -> np.ndarray:
    """The safety layer's formula written plainly with np.clip (what main computed before the
    layer was rewritten in in-place ufuncs): a replay must match it to the bit."""
    command = np.clip(rest + amplitude * (target - rest), LOWER, UPPER)
    if last is None:
        return command
    max_step = VMAX * dt
    command = last + np.clip(command - last, -max_step, max_step)
    return np.clip(command, np.minimum(LOWER, last), np.maximum(UPPER, last))


@settings(max_examples=300, deadline=None)
@given(
    targets=st.lists(arrays(float, N, elements=finite), min_size=1, max_size=20),
    start=arrays(float, N, elements=st.floats(-3, 3)),
    rest=arrays(float, N, elements=st.floats(-0.5, 0.5)),
    dt=st.floats(1e-4, 0.05),
    amplitudes=st.lists(st.floats(0, 1), min_size=20, max_size=20),
)
def test_commands_are_the_plain_formula_to_the_bit(
    targets: list[np.ndarray],
    start: np.ndarray,
    rest: np.ndarray,
    dt: float,
    amplitudes: list[float],
) -> None:
    # Starts outside the limits too: the layer's shortcut once every joint is inside (the
    # bounds are then the limits) must give what the general bounds give.
    layer = SafetyLayer(LOWER, UPPER, VMAX, ramp_s=1.0, rest_rad=rest)
    layer.reset(start)
    last = start
    rest_inside = np.clip(rest, LOWER, UPPER)
    for target, amplitude in zip(targets, amplitudes, strict=False):
        command = layer.filter(target, dt, amplitude)
        expected = reference_filter(last, target, rest_inside, dt, amplitude)
        assert command.tobytes() == expected.tobytes()
        last = command


def test_without_a_reset_the_first_command_is_clipped_and_the_next_slew_limited() -> None:
    layer = SafetyLayer(LOWER, UPPER, VMAX, ramp_s=1.0)
    first = layer.filter(np.full(N, 9.0), 0.01)
    assert first.tobytes() == np.clip(np.full(N, 9.0), LOWER, UPPER).tobytes()
    second = layer.filter(np.full(N, -9.0), 0.01)
    assert np.allclose(second, np.maximum(first - VMAX * 0.01, LOWER))


def test_an_infinite_target_is_refused_even_among_huge_finite_ones() -> None:
    layer = SafetyLayer(LOWER, UPPER, VMAX, ramp_s=1.0)
    layer.reset(np.zeros(N))
    huge = np.full(N, 1e308)  # their sum overflows; they are finite and clipped
    assert np.array_equal(layer.filter(huge, 0.01), np.minimum(VMAX * 0.01, UPPER))
    bad = huge.copy()
    bad[2] = np.inf
    with pytest.raises(SafetyLimitError, match=r"joints \[2\]"):
        layer.filter(bad, 0.01)
