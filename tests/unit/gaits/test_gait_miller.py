from __future__ import annotations

import math

import numpy as np
import pytest

from snakebot.errors import GaitError
from snakebot.gaits import get_spec, make_gait, parse_set_options
from snakebot.gaits.miller import CHANNEL_CHOICES
from snakebot.gaits.spec import coerce_value

NAMES = ("rectilinear", "undulation", "miller_sidewinding")


@pytest.mark.parametrize("name", NAMES)
def test_defaults_are_valid_and_build_for_whole_segments(name: str) -> None:
    spec = get_spec(name)
    for param in spec.params:
        assert param.doc and coerce_value(name, param, param.default) == param.default
    gait = make_gait(name, 30)  # 10 segments of yaw, pitch, axial
    times = np.linspace(0.0, 2.0, 7)
    batch = gait.targets(times)
    assert batch.shape == (7, 30) and np.isfinite(batch).all()
    np.testing.assert_allclose(batch[3], gait.targets(float(times[3])))
    assert gait.period_s == pytest.approx(1.0)


def _channels(targets: np.ndarray, count: int = 3) -> np.ndarray:
    """(T, N) -> (T, S, channels)."""
    return targets.reshape(targets.shape[0], -1, count)


def test_rectilinear_is_a_compression_wave_from_head_to_tail() -> None:
    gait = make_gait("rectilinear", 18)
    table = _channels(gait.targets(np.arange(205) / 204))
    assert np.abs(table[:, :, :2]).max() == 0.0  # no bending
    axial = table[:, :, 2]
    assert np.abs(axial).max() == pytest.approx(0.3, abs=1e-3)
    # Each segment plays its head-side neighbour's strain 1/12 period later: half a wave over
    # six segments, travelling head -> tail.
    np.testing.assert_allclose(axial[17:, 1:], axial[:-17, :-1], atol=1e-12)


def test_square_wave_takes_only_the_amplitudes() -> None:
    gait = make_gait("rectilinear", 6, {"shape": "square", "amplitude": 0.2})
    values = set(np.round(gait.targets(np.linspace(0.01, 0.99, 50)).ravel(), 12))
    assert values <= {0.0, 0.2, -0.2}


def test_undulation_bends_left_and_right_only() -> None:
    table = _channels(make_gait("undulation", 30).targets(np.linspace(0, 1, 50)))
    assert np.abs(table[:, :, 1:]).max() == 0.0
    assert np.abs(table[:, :, 0]).max() == pytest.approx(0.4, abs=0.01)


def test_sidewinding_adds_a_vertical_wave_90_degrees_out_of_phase_over_l_over_1_4() -> None:
    gait = make_gait("miller_sidewinding", 30)
    t = np.linspace(0, 1, 2001)
    table = _channels(gait.targets(t))
    yaw, pitch = table[:, 0, 0], table[:, 0, 1]
    assert t[np.argmax(yaw)] - t[np.argmax(pitch)] == pytest.approx(0.25, abs=1e-3)
    # wavelength L / 1.4: segment 10/1.4 segments behind is one period behind
    snapshot = table[0, :, 0]
    expected = 0.4 * np.sin(-2 * math.pi * 1.4 * np.arange(10) / 10)
    np.testing.assert_allclose(snapshot, expected, atol=1e-12)


def test_channels_follow_the_bodys_layout() -> None:
    gait = make_gait("undulation", 8, {"channels": "pitch,yaw"})
    table = _channels(gait.targets(np.linspace(0, 1, 20)), 2)
    assert np.abs(table[:, :, 0]).max() == 0.0 and np.abs(table[:, :, 1]).max() > 0.3
    assert set(CHANNEL_CHOICES) >= {"yaw,pitch,axial", "yaw,pitch", "axial", "pitch,axial"}


@pytest.mark.parametrize(
    ("name", "n", "params", "match"),
    [
        ("rectilinear", 8, {}, "not whole segments of 3 channels"),
        ("rectilinear", 6, {"channels": "yaw,pitch"}, "axial channel"),
        ("miller_sidewinding", 6, {"channels": "yaw"}, "pitch channel"),
        ("undulation", 6, {"channels": "yaw,roll"}, "expected one of"),
        ("undulation", 6, {"waves": math.inf}, "waves"),
    ],
)
def test_mismatched_bodies_are_refused_clearly(
    name: str, n: int, params: dict[str, object], match: str
) -> None:
    with pytest.raises(GaitError, match=match):
        make_gait(name, n, params)


def test_set_options_parse_for_the_cli() -> None:
    assert parse_set_options("rectilinear", ["shape=square", "omega=pi"]) == {
        "shape": "square",
        "omega": pytest.approx(math.pi),
    }
    assert get_spec("rectilinear").default_search == ("amplitude", "omega", "waves")
