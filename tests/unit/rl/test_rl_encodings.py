"""The encodings turn actions into the gait classes `snakebot run` plays, and fix the seed's
faults: the phase-shifted DFT is a true shift at every step, the sinusoid can steer."""

from __future__ import annotations

import math

import numpy as np
import pytest

from snakebot.errors import ConfigError
from snakebot.gaits import CompoundGait, DftGait, DftShiftGait, SerpenoidGait, SimpleGait
from snakebot.rl.encodings import ENCODINGS, GaitClock, make_encoding

N = 8
LOWER, UPPER = np.full(N, -1.5), np.full(N, 1.5)


def encoding(name: str, **kwargs: float) -> object:
    return make_encoding(name, N, LOWER, UPPER, **kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("name", "cls", "dim"),
    [
        ("simple", SimpleGait, N),
        ("sinusoid", SerpenoidGait, 4),
        ("dft", DftGait, 5),
        ("dft_shift", DftShiftGait, 5),
        ("compound", CompoundGait, 9),
    ],
)
def test_each_encoding_makes_the_gait_class_run_plays(name: str, cls: type, dim: int) -> None:
    enc = make_encoding(name, N, LOWER, UPPER)
    assert enc.action_dim == dim
    gait = enc.gait(np.linspace(-1, 1, dim))
    assert isinstance(gait, cls)
    assert gait.joint_count == N
    # Actions outside the box are clipped, not extrapolated past the limits.
    wild = enc.gait(np.full(dim, 50.0))
    assert np.all(np.abs(GaitClock(enc).targets(wild)) <= 1.5 + 1e-12)


def band_limited(coefficients: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """The continuous interpolant of rfft bins 0..K-1 (forward-normalised) at positions."""
    out = np.full(positions.shape, coefficients[0].real)
    for k in range(1, coefficients.size):
        out += 2 * np.real(coefficients[k] * np.exp(2j * np.pi * k * positions / N))
    return out


@pytest.mark.parametrize("shift", [0.0, 0.37, 1.5, 2.91, 6.999])
def test_dft_shift_is_a_true_fractional_shift(shift: float) -> None:
    enc = make_encoding("dft_shift", N, LOWER, UPPER, dft_bins=3)
    action = np.array([0.3, 0.9, -0.4, 0.7, 0.8])
    gait = enc.gait(action)
    assert isinstance(gait, DftShiftGait)
    clock = GaitClock(enc)
    clock.reset(2 * math.pi * shift / N)  # the phase of a shift by `shift` joints
    got = clock.targets(gait)
    bins = np.array(gait.coefficients[0::2]) + 1j * np.array(gait.coefficients[1::2])
    expected = band_limited(bins, np.arange(N) - shift)
    np.testing.assert_allclose(got, expected, atol=1e-12)
    # A shift keeps the wave's energy: same RMS about the mean at every phase (the seed's
    # rotation lost a third of it between integer shifts).
    clock.reset(0.0)
    base = clock.targets(gait)
    assert np.std(got) == pytest.approx(np.std(base), rel=1e-9)


def test_dft_bins_stop_below_nyquist() -> None:
    with pytest.raises(ConfigError, match=r"dft_bins.*Nyquist"):
        make_encoding("dft_shift", N, LOWER, UPPER, dft_bins=5)  # bin 4 is Nyquist for N = 8
    assert make_encoding("dft_shift", N, LOWER, UPPER, dft_bins=4).action_dim == 7


def test_dft_actions_never_leave_the_joint_limits_so_the_shape_is_never_rescaled() -> None:
    enc = make_encoding("dft_shift", N, LOWER, UPPER)
    clock = GaitClock(enc)
    for corner in np.array(np.meshgrid(*[[-1, 1]] * 5)).reshape(5, -1).T:
        gait = enc.gait(corner)
        for phase in np.linspace(0, 2 * math.pi, 17):
            clock.reset(phase)
            assert np.abs(clock.targets(gait)).max() <= 1.5


def test_sinusoid_offset_steers() -> None:
    enc = make_encoding("sinusoid", N, LOWER, UPPER)
    clock = GaitClock(enc)
    left, straight = enc.gait(np.array([0, 0, 0, 1.0])), enc.gait(np.zeros(4))
    mean = []
    for gait in (left, straight):
        poses = []
        for phase in np.linspace(0, 2 * math.pi, 64, endpoint=False):
            clock.reset(phase)
            poses.append(clock.targets(gait))
        mean.append(float(np.mean(poses)))
    assert mean[0] == pytest.approx(0.4, abs=1e-9)  # the full offset bends every joint
    assert mean[1] == pytest.approx(0.0, abs=1e-9)


def test_a_new_frequency_continues_the_wave_without_a_jump() -> None:
    enc = make_encoding("sinusoid", N, LOWER, UPPER)
    clock = GaitClock(enc)
    slow, fast = enc.gait(np.array([0, -1.0, 0, 0])), enc.gait(np.array([0, 1.0, 0, 0]))
    for _ in range(7):
        clock.advance(slow, 0.02)
    before = clock.targets(slow)
    after = clock.targets(fast)  # same phase, same amplitude and lag: the same pose
    np.testing.assert_allclose(before, after, atol=1e-12)
    clock.advance(fast, 0.02)
    assert clock.phase_rad[0] == pytest.approx(
        7 * 0.02 * 2 * math.pi * 0.1 + 0.02 * 2 * math.pi * 1.5
    )


def test_static_encodings_observe_a_clock_phase() -> None:
    for name in ("simple", "dft"):
        enc = make_encoding(name, N, LOWER, UPPER, phase_hz=0.5)
        clock = GaitClock(enc)
        gait = enc.gait(np.zeros(enc.action_dim))
        clock.advance(gait, 0.5)  # a quarter turn at 0.5 Hz
        np.testing.assert_allclose(clock.observed(), [1.0, 0.0], atol=1e-12)


def test_unknown_encoding_names_the_choices() -> None:
    with pytest.raises(ConfigError, match="sinusoid"):
        make_encoding("rotating", N, LOWER, UPPER)
    assert set(ENCODINGS) == {"simple", "sinusoid", "dft", "dft_shift", "compound"}
