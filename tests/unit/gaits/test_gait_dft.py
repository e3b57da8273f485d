import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from snakebot.errors import GaitError
from snakebot.gaits import DftGait, DftShiftGait, dft_coefficients_from_pose, make_gait

HALF_PI = math.pi / 2
in_limit = st.floats(-HALF_PI, HALF_PI, allow_nan=False)
poses = st.integers(1, 40).flatmap(lambda n: st.lists(in_limit, min_size=n, max_size=n))


@settings(deadline=None)
@given(pose=poses)
def test_full_coefficients_reproduce_any_in_limit_pose(pose: list[float]) -> None:
    coefficients = dft_coefficients_from_pose(pose)
    assert len(coefficients) == 2 * (len(pose) // 2 + 1)
    gait = DftGait(len(pose), coefficients)
    np.testing.assert_allclose(gait.targets(0.0), pose, rtol=0, atol=1e-12)
    assert gait.period_s is None


@settings(deadline=None)
@given(
    n=st.integers(2, 24),
    coefficients=st.lists(st.floats(-5.0, 5.0), min_size=4, max_size=4),
    lower=st.floats(-2.0, -0.1),
    upper=st.floats(0.1, 2.0),
)
def test_scaling_keeps_shape_and_lands_within_limits(
    n: int, coefficients: list[float], lower: float, upper: float
) -> None:
    loose = DftGait(n, tuple(coefficients), lower_rad=(-1e9,) * n, upper_rad=(1e9,) * n)
    fitted = DftGait(n, tuple(coefficients), lower_rad=(lower,) * n, upper_rad=(upper,) * n)
    raw, pose = loose.targets(0.0), fitted.targets(0.0)
    assert np.all(pose >= lower) and np.all(pose <= upper)
    with np.errstate(over="ignore"):  # a subnormal raw angle overflows the ratio to inf: fine
        factor = min([1.0, *(upper / x for x in raw if x > 0), *(lower / x for x in raw if x < 0)])
    np.testing.assert_allclose(pose, factor * raw, atol=1e-9)


def test_pose_inside_limits_is_untouched_and_outside_is_scaled_to_touch() -> None:
    gait = make_gait("dft", 12, {"coefficients": (0.0, 0.0, 0.0, -0.2)})
    wave = 0.4 * np.sin(2 * np.pi * np.arange(12) / 12)
    np.testing.assert_allclose(gait.targets(0.0), wave, atol=1e-12)
    big = make_gait("dft", 12, {"coefficients": (0.0, 0.0, 0.0, -0.2), "scale": 10.0})
    assert np.max(np.abs(big.targets(0.0))) == pytest.approx(HALF_PI)
    np.testing.assert_allclose(big.targets(0.0), gait.targets(0.0) * HALF_PI / 0.4, atol=1e-12)


def test_limits_from_make_gait_are_used() -> None:
    lower, upper = np.full(8, -0.1), np.full(8, 1.0)
    gait = make_gait("dft", 8, {"scale": 3.0}, lower_rad=lower, upper_rad=upper)
    pose = gait.targets(0.0)
    assert pose.min() == pytest.approx(-0.1) and pose.max() <= 1.0


@pytest.mark.parametrize(
    ("coefficients", "match"),
    [((0.1, 0.2, 0.3), "even count"), ((0.0,) * 16, "N//2"), ((), "even count")],
)
def test_bad_coefficients_raise(coefficients: tuple[float, ...], match: str) -> None:
    with pytest.raises(GaitError, match=match):
        DftGait(12, coefficients)


def test_limits_must_contain_zero_and_have_length_n() -> None:
    with pytest.raises(GaitError, match="contain 0"):
        DftGait(4, lower_rad=(0.1,) * 4, upper_rad=(1.0,) * 4)
    with pytest.raises(GaitError, match=r"dft_shift\.upper_rad"):
        DftShiftGait(4, upper_rad=(1.0,) * 3)


@settings(deadline=None)
@given(
    data=st.data(),
    n=st.integers(1, 24),
    shift=st.integers(-40, 40),
)
def test_integer_shift_equals_a_roll_of_the_joints(data: st.DataObject, n: int, shift: int) -> None:
    pose = np.array(data.draw(st.lists(in_limit, min_size=n, max_size=n)))
    coefficients = dft_coefficients_from_pose(pose)
    by_offset = DftShiftGait(n, coefficients, shift_rate=0.0, shift0=float(shift))
    np.testing.assert_allclose(by_offset.targets(0.0), np.roll(pose, shift), atol=1e-9)
    by_time = DftShiftGait(n, coefficients, shift_rate=2.0)
    np.testing.assert_allclose(by_time.targets(shift / 2.0), np.roll(pose, shift), atol=1e-9)


def test_constant_coefficients_travel_head_to_tail() -> None:
    bump = np.zeros(16)
    bump[2:5] = (0.3, 0.6, 0.3)
    gait = DftShiftGait(16, dft_coefficients_from_pose(bump), shift_rate=4.0)
    times = np.linspace(0.0, 2.0, 81)
    peaks = np.argmax(gait.targets(times), axis=1)
    assert peaks[0] == 3
    assert peaks[-1] == 11
    assert np.all(np.diff(peaks) >= 0)


def test_shift_period_repeats_the_motion() -> None:
    gait = make_gait("dft_shift", 12, {"shift_rate": -3.0})
    assert gait.period_s == pytest.approx(4.0)
    times = np.linspace(0.0, 4.0, 9)
    np.testing.assert_allclose(gait.targets(times), gait.targets(times + 4.0), atol=1e-9)
    assert make_gait("dft_shift", 12, {"shift_rate": 0.0}).period_s is None
