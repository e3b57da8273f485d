import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from snakebot.errors import GaitError
from snakebot.gaits import KeyframeGait, make_gait
from snakebot.gaits.keyframes import default_poses

POSES = np.array([[0.0, 0.2, -0.1], [0.4, -0.2, 0.3], [-0.3, 0.1, 0.5]])


def _gait(**kwargs: object) -> KeyframeGait:
    params: dict[str, object] = {"poses": tuple(POSES.ravel()), "durations": (0.5, 1.0, 0.25)}
    params.update(kwargs)
    gait = make_gait("keyframes", 3, params)
    assert isinstance(gait, KeyframeGait)
    return gait


@pytest.mark.parametrize("interpolation", ["linear", "cubic"])
@pytest.mark.parametrize("mirror", [0, 1])
def test_passes_through_each_keyframe_at_its_time(interpolation: str, mirror: int) -> None:
    gait = _gait(interpolation=interpolation, mirror=mirror)
    expected = np.vstack([POSES, -POSES]) if mirror else POSES
    times = np.array([0.0, 0.5, 1.5, 1.75, 2.25, 3.25])[: len(expected)]
    np.testing.assert_allclose(gait.keyframe_times_s, times)
    for cycle in (0, 1, -2):
        shifted = times + cycle * gait.period_s
        np.testing.assert_allclose(gait.targets(shifted), expected, atol=1e-9)


def test_linear_midpoint_is_the_average_of_neighbouring_keyframes() -> None:
    gait = _gait(interpolation="linear")
    np.testing.assert_allclose(gait.targets(0.25), (POSES[0] + POSES[1]) / 2, atol=1e-12)
    np.testing.assert_allclose(gait.targets(1.0), (POSES[1] + POSES[2]) / 2, atol=1e-12)
    np.testing.assert_allclose(gait.targets(1.625), (POSES[2] + POSES[0]) / 2, atol=1e-12)


@settings(deadline=None)
@given(t=st.floats(-10.0, 10.0), interpolation=st.sampled_from(["linear", "cubic"]))
def test_mirroring_negates_the_second_half_of_the_cycle(t: float, interpolation: str) -> None:
    gait = _gait(mirror=1, interpolation=interpolation)
    assert gait.period_s == pytest.approx(3.5)
    np.testing.assert_allclose(gait.targets(t + 1.75), -gait.targets(t), atol=1e-9)


def test_cubic_is_periodic_and_smooth_across_the_wrap() -> None:
    gait = _gait(interpolation="cubic")
    period, h = gait.period_s, 1e-5
    for knot in (*gait.keyframe_times_s, period):
        left = (gait.targets(knot) - gait.targets(knot - h)) / h
        right = (gait.targets(knot + h) - gait.targets(knot)) / h
        np.testing.assert_allclose(left, right, atol=1e-3)
    np.testing.assert_allclose(gait.targets(0.3), gait.targets(0.3 + period), atol=1e-9)


def test_linear_has_a_kink_at_keyframes() -> None:
    gait = _gait(interpolation="linear")
    h = 1e-5
    left = (gait.targets(0.5) - gait.targets(0.5 - h)) / h
    right = (gait.targets(0.5 + h) - gait.targets(0.5)) / h
    assert np.abs(left - right).max() > 0.1


def test_single_duration_applies_to_every_keyframe() -> None:
    gait = _gait(durations=(0.4,))
    np.testing.assert_allclose(gait.keyframe_times_s, [0.0, 0.4, 0.8])
    assert gait.period_s == pytest.approx(1.2)


def test_error_based_advance_waits_for_the_measured_pose() -> None:
    gait = _gait(interpolation="linear", advance="error", error_threshold_rad=0.05, timeout_s=10.0)
    np.testing.assert_allclose(gait.command(0.0, POSES[0]), POSES[0])
    np.testing.assert_allclose(gait.command(0.25, POSES[0]), (POSES[0] + POSES[1]) / 2)
    for t in (0.5, 1.0, 1.75, 3.0):
        np.testing.assert_allclose(gait.command(t, POSES[0]), POSES[1])
    assert not np.allclose(gait.targets(1.75), POSES[1])
    np.testing.assert_allclose(gait.command(3.1, POSES[1] + 0.04), POSES[1])
    np.testing.assert_allclose(gait.command(3.6, POSES[1]), (POSES[1] + POSES[2]) / 2)
    gait.reset()
    np.testing.assert_allclose(gait.command(5.0, None), POSES[0])


def test_error_based_advance_gives_up_after_the_timeout() -> None:
    gait = _gait(interpolation="linear", advance="error", timeout_s=1.0)
    gait.command(0.0, POSES[0])
    np.testing.assert_allclose(gait.command(1.4, POSES[0]), POSES[1])
    np.testing.assert_allclose(gait.command(1.6, POSES[0]), POSES[1])
    np.testing.assert_allclose(gait.command(2.1, POSES[1]), (POSES[1] + POSES[2]) / 2, atol=1e-12)


def test_time_advance_command_equals_targets() -> None:
    gait = _gait()
    np.testing.assert_allclose(gait.command(1.3, POSES[0]), gait.targets(1.3))


def test_default_is_a_four_pose_cycle_for_any_n() -> None:
    for n in (2, 12, 33):
        gait = make_gait("keyframes", n)
        assert isinstance(gait, KeyframeGait)
        assert gait.keyframe_poses.shape == (4, n)
        np.testing.assert_allclose(gait.keyframe_poses[2], -gait.keyframe_poses[0], atol=1e-12)
        assert len(default_poses(n)) == 4 * n


@pytest.mark.parametrize(
    ("params", "match"),
    [
        ({"poses": (0.1, 0.2)}, r"keyframes\.poses"),
        ({"durations": (1.0, 2.0)}, r"keyframes\.durations"),
        ({"durations": (0.0,)}, r"keyframes\.durations"),
        ({"interpolation": "spline"}, r"keyframes\.interpolation"),
        ({"advance": "never"}, r"keyframes\.advance"),
        ({"mirror": 2.0}, r"keyframes\.mirror"),
        ({"error_threshold_rad": 0.0}, "error_threshold_rad"),
    ],
)
def test_bad_parameters_raise(params: dict[str, object], match: str) -> None:
    with pytest.raises(GaitError, match=match):
        _gait(**params)


def test_measured_pose_of_wrong_shape_raises() -> None:
    gait = _gait(advance="error")
    gait.command(0.0, POSES[0])
    with pytest.raises(GaitError, match="measured_rad"):
        gait.command(2.0, np.zeros(5))
    with pytest.raises(GaitError, match="joint_count"):
        KeyframeGait(0)
