import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from snakebot.errors import GaitError
from snakebot.gaits import SerpenoidGait


@settings(deadline=None)
@given(
    t=st.floats(-20.0, 20.0),
    joint=st.integers(0, 11),
    phase_lag=st.floats(0.05, 2.0),
    omega=st.floats(0.2, 12.0),
)
def test_joint_i_is_joint_0_delayed_by_i_lag_over_omega(
    t: float, joint: int, phase_lag: float, omega: float
) -> None:
    gait = SerpenoidGait(12, amplitude=0.5, omega=omega, phase_lag=phase_lag, offset=0.1)
    delayed = t - joint * phase_lag / omega
    assert gait.targets(t)[joint] == pytest.approx(gait.targets(delayed)[0], abs=1e-9)


def test_joint_1_peaks_after_joint_0() -> None:
    gait = SerpenoidGait(8, amplitude=0.4, omega=math.pi, phase_lag=0.7)
    times = np.linspace(0.0, gait.period_s or 0.0, 2001)
    angles = gait.targets(times)
    delay = times[np.argmax(angles[:, 1])] - times[np.argmax(angles[:, 0])]
    assert delay == pytest.approx(0.7 / math.pi, abs=2e-3)


def test_targets_are_the_serpenoid_formula() -> None:
    gait = SerpenoidGait(5, amplitude=0.3, omega=2.0, phase_lag=0.5, offset=-0.1)
    joints = np.arange(5)
    expected = 0.3 * np.sin(2.0 * 1.25 - 0.5 * joints) - 0.1
    np.testing.assert_allclose(gait.targets(1.25), expected, atol=1e-12)


def test_vectorised_targets_equal_stacked_scalar_calls() -> None:
    gait = SerpenoidGait(12)
    times = np.linspace(-1.0, 3.0, 17)
    stacked = np.stack([gait.targets(float(t)) for t in times])
    assert gait.targets(times).shape == (17, 12)
    np.testing.assert_allclose(gait.targets(times), stacked, atol=1e-12)


def test_period_and_defaults() -> None:
    gait = SerpenoidGait(8)
    assert (gait.amplitude, gait.omega, gait.phase_lag, gait.offset) == (0.4, math.pi, 0.7, 0.0)
    assert gait.period_s == pytest.approx(2.0)
    np.testing.assert_allclose(gait.targets(0.3), gait.targets(2.3), atol=1e-12)
    assert SerpenoidGait(8, omega=-math.pi).period_s == pytest.approx(2.0)
    assert SerpenoidGait(8, omega=0.0).period_s is None


@pytest.mark.parametrize("bad", [np.zeros((2, 2)), math.nan, [0.0, math.inf]])
def test_bad_times_raise(bad: object) -> None:
    with pytest.raises(GaitError, match="time_s"):
        SerpenoidGait(4).targets(bad)  # type: ignore[arg-type]


def test_bad_construction_raises() -> None:
    with pytest.raises(GaitError, match="joint_count"):
        SerpenoidGait(0)
    with pytest.raises(GaitError, match=r"serpenoid\.amplitude"):
        SerpenoidGait(4, amplitude=math.nan)


@pytest.mark.parametrize(
    "params",
    [{}, {"omega": -2.5, "offset": 0.1}, {"amplitude": 1.1, "phase_lag": -0.9, "omega": 7.0}],
)
def test_the_control_loops_scalar_time_gives_the_bits_of_the_array_path(
    params: dict[str, float],
) -> None:
    """The loop asks one float time a cycle (a shorter path); a replay or the batched engine
    asks times (T,): the same floats, to the bit, at every time, zero and negative ones too."""
    gait = SerpenoidGait(12, **params)
    times = np.concatenate([[0.0, -0.0, -1.5], np.linspace(0.0, 40.0, 4001)])
    rows = gait.targets(times)
    for time_s, row in zip(times.tolist(), rows, strict=True):
        assert gait.targets(time_s).tobytes() == row.tobytes(), time_s
