import itertools
import math

import numpy as np
import pytest

from snakebot.errors import GaitError
from snakebot.gaits import CompoundGait, gait_names, get_spec, make_gait, resolve_params

PRESETS = ("lateral_undulation", "sidewinding", "rolling", "linear_progression", "turn_in_place")
TIMES = np.linspace(0.0, 4.0, 41)


def test_matches_the_gait_equation() -> None:
    gait = CompoundGait(
        6,
        amplitude_even=0.5,
        amplitude_odd=0.3,
        offset_even=0.1,
        offset_odd=-0.2,
        spatial_freq_even=0.4,
        spatial_freq_odd=0.9,
        temporal_freq_even=2.0,
        temporal_freq_odd=3.0,
        phase_shift=0.7,
    )
    t = 0.8
    pose = gait.targets(t)
    assert pose[4] == pytest.approx(0.1 + 0.5 * math.sin(0.4 * 4 - 2.0 * t))
    assert pose[3] == pytest.approx(-0.2 + 0.3 * math.sin(0.9 * 3 - 3.0 * t + 0.7))


def test_odd_amplitude_zero_holds_odd_joints_at_their_offset() -> None:
    gait = CompoundGait(12, amplitude_odd=0.0, offset_odd=0.25)
    poses = gait.targets(TIMES)
    np.testing.assert_allclose(poses[:, 1::2], 0.25, atol=1e-12)
    assert np.ptp(poses[:, 0::2], axis=0).min() > 0.5


def test_even_amplitude_zero_holds_even_joints_at_their_offset() -> None:
    poses = CompoundGait(12, amplitude_even=0.0, offset_even=-0.1).targets(TIMES)
    np.testing.assert_allclose(poses[:, 0::2], -0.1, atol=1e-12)
    assert np.ptp(poses[:, 1::2], axis=0).min() > 0.5


def test_presets_are_registered_with_distinct_defaults() -> None:
    assert set(PRESETS) <= set(gait_names())
    defaults = {name: resolve_params(name) for name in PRESETS}
    for a, b in itertools.combinations(PRESETS, 2):
        assert defaults[a] != defaults[b], (a, b)
    for name in PRESETS:
        assert get_spec(name).param_names == get_spec("compound").param_names
        assert "CMU" in get_spec(name).summary or "snakelib" in get_spec(name).summary


@pytest.mark.parametrize("name", PRESETS)
def test_presets_respect_the_servo_speed_budget(name: str) -> None:
    p = resolve_params(name)
    for plane in ("even", "odd"):
        amplitude, omega = p[f"amplitude_{plane}"], p[f"temporal_freq_{plane}"]
        assert isinstance(amplitude, float) and isinstance(omega, float)
        assert abs(amplitude * omega) < 5.0
    gait = make_gait(name, 12)
    speed = np.abs(np.diff(gait.targets(np.linspace(0.0, 2.0, 2001)), axis=0)) / 1e-3
    assert speed.max() < 5.0


def test_lateral_undulation_moves_only_yaw_joints() -> None:
    poses = make_gait("lateral_undulation", 12).targets(TIMES)
    np.testing.assert_allclose(poses[:, 1::2], 0.0, atol=1e-12)
    assert np.abs(poses[:, 0::2]).max() == pytest.approx(0.6, abs=0.01)


def test_sidewinding_uses_the_reference_parameters() -> None:
    p = resolve_params("sidewinding")
    assert p["amplitude_even"] == p["amplitude_odd"] == 0.6
    assert p["spatial_freq_even"] == p["spatial_freq_odd"] == 0.5
    assert p["phase_shift"] == pytest.approx(math.pi / 4)
    assert make_gait("sidewinding", 12).period_s == pytest.approx(2.0)


def test_rolling_is_an_arc_with_equal_joints_per_plane() -> None:
    poses = make_gait("rolling", 12).targets(TIMES)
    assert np.ptp(poses[:, 0::2], axis=1).max() < 1e-12
    assert np.ptp(poses[:, 1::2], axis=1).max() < 1e-12
    assert np.abs(poses).max() == pytest.approx(0.3, abs=0.01)


def test_half_flip_negates_the_phase_shift_on_the_rear_half() -> None:
    plain = CompoundGait(12, phase_shift=0.6)
    flipped = CompoundGait(12, phase_shift=0.6, half_flip=True)
    mirrored = CompoundGait(12, phase_shift=-0.6)
    a, b, c = plain.targets(TIMES), flipped.targets(TIMES), mirrored.targets(TIMES)
    np.testing.assert_allclose(b[:, :6], a[:, :6], atol=1e-12)
    np.testing.assert_allclose(b[:, 6:], c[:, 6:], atol=1e-12)
    assert np.abs(b[:, 7::2] - a[:, 7::2]).max() > 0.1
    np.testing.assert_allclose(b[:, 6::2], a[:, 6::2], atol=1e-12)
    assert make_gait("turn_in_place", 12).half_flip  # type: ignore[attr-defined]


def test_offset_split_negates_offsets_on_the_rear_half() -> None:
    poses = make_gait("linear_progression", 12).targets(TIMES)
    np.testing.assert_allclose(poses[:, 0:6:2], 0.3, atol=1e-12)
    np.testing.assert_allclose(poses[:, 6::2], -0.3, atol=1e-12)
    split = CompoundGait(8, amplitude_even=0, amplitude_odd=0, offset_odd=0.2, offset_split=True)
    np.testing.assert_allclose(split.targets(0.0)[1::2], [0.2, 0.2, -0.2, -0.2])


def test_linear_progression_wave_runs_tail_to_head() -> None:
    gait = make_gait("linear_progression", 12)
    step = 2 * (math.pi / 4) / math.pi
    for t in (0.0, 0.3, 1.1):
        later, now = gait.targets(t + step), gait.targets(t)
        np.testing.assert_allclose(later[1:-2:2], now[3::2], atol=1e-9)


def test_period_falls_back_to_the_odd_frequency() -> None:
    assert CompoundGait(4, temporal_freq_even=0.0, temporal_freq_odd=2.0).period_s == pytest.approx(
        math.pi
    )
    assert CompoundGait(4, temporal_freq_even=0.0, temporal_freq_odd=0.0).period_s is None


def test_errors_name_the_preset() -> None:
    with pytest.raises(GaitError, match=r"turn_in_place\.half_flip"):
        make_gait("turn_in_place", 12, {"half_flip": 0.5})
    with pytest.raises(GaitError, match=r"sidewinding\.phase_shift"):
        make_gait("sidewinding", 12, {"phase_shift": "quarter"})
