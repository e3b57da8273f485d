"""The action encodings of "Serpentile Locomotion" as maps from a policy's action to a gait.

A policy acts in ``[-1, 1]^d``; each encoding turns one action into a ``PhasedGait`` from
``snakebot.gaits`` (the same classes ``snakebot run`` plays), so a learned policy and a hand-made
gait share one formula. The phases those gaits turn are integrated here, by ``GaitClock``, from
the rates of whichever gait is current, so a policy that changes the frequency every step never
makes the wave jump.

- ``simple``: one target per joint (identity), mapped onto the joint limits.
- ``sinusoid``: serpenoid amplitude, frequency, phase lag and an offset (the seed's sinusoid
  cannot steer; the offset is the CMU gait equation's turning term).
- ``dft``: K rfft bins of the pose (bin 0 = the mean angle), a static pose each step.
- ``dft_shift``: the same bins shifted along the body at ``phase_hz`` laps per second, a true
  (band-limited) shift at every step: the bins never include the Nyquist bin, whose fractional
  shift a real signal cannot carry, and their amplitudes fit the joint limits so the pose is
  never rescaled mid-lap.
- ``compound``: the nine numbers of the CMU gait equation (two waves, two phases).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from snakebot.errors import ConfigError
from snakebot.gaits import (
    CompoundGait,
    DftGait,
    DftShiftGait,
    PhasedGait,
    SerpenoidGait,
    SimpleGait,
)
from snakebot.gaits.base import FloatArray

ENCODINGS = ("simple", "sinusoid", "dft", "dft_shift", "compound")
SEED_ENCODINGS = ("simple", "sinusoid", "dft", "dft_shift")

# Ranges the actions span, in the gaits' own units. Frequencies stop at 1.5 Hz: the servos' speed
# limit (safety layer) flattens bigger waves before that.
AMPLITUDE_RAD = (0.0, 1.0)
FREQUENCY_HZ = (0.1, 1.5)
PHASE_LAG_RAD = (0.2, 1.2)
OFFSET_RAD = (-0.4, 0.4)
SPATIAL_RAD = (0.1, math.pi / 2)
PHASE_SHIFT_RAD = (-math.pi, math.pi)
DFT_MEAN_FRACTION = 0.2  # of the joint limit: bin 0, the steering bend


def lerp(action: float, bounds: tuple[float, float]) -> float:
    """Map an action in [-1, 1] linearly onto (low, high); -1 -> low, +1 -> high."""
    low, high = bounds
    return low + (float(action) + 1.0) * 0.5 * (high - low)


def unlerp(value: float, bounds: tuple[float, float]) -> float:
    """The action in [-1, 1] that ``lerp`` maps onto ``value`` in (low, high)."""
    low, high = bounds
    return 2.0 * (float(value) - low) / (high - low) - 1.0


@dataclass(frozen=True)
class Encoding:
    """How one action (d,) in [-1, 1] becomes a gait for N joints, and how many phases it turns.

    ``phase_count`` is the P of the gaits it makes (0 for the static poses ``simple`` and
    ``dft``); ``clock_hz`` is the rate of the reference phase that static encodings observe
    instead (so a policy can still make a periodic gait out of them).
    """

    name: str
    joint_count: int
    action_dim: int
    phase_count: int
    clock_hz: float
    make: Callable[[FloatArray], PhasedGait]

    def gait(self, action: FloatArray) -> PhasedGait:
        """The gait for ``action`` (d,); values outside [-1, 1] are clipped first."""
        return self.make(np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0))

    @property
    def observed_phases(self) -> int:
        """How many phases the observation carries (sin, cos) of: P, or 1 clock phase."""
        return max(self.phase_count, 1)


def make_encoding(
    name: str,
    joint_count: int,
    lower_rad: FloatArray,
    upper_rad: FloatArray,
    *,
    phase_hz: float = 0.5,
    dft_bins: int = 3,
) -> Encoding:
    """The encoding ``name`` for a snake with joint limits (N,) in rad.

    ``phase_hz``: laps per second of the dft_shift wave, and the clock of static encodings.
    ``dft_bins``: K, the rfft bins (0..K-1) the dft encodings act on. Raises ConfigError naming
    the option when a value cannot work.
    """
    n = joint_count
    lower = np.asarray(lower_rad, dtype=np.float64)
    upper = np.asarray(upper_rad, dtype=np.float64)
    if not (phase_hz > 0 and math.isfinite(phase_hz)):
        raise ConfigError("phase_hz", "", f"expected a positive frequency in Hz, got {phase_hz}")
    limit = float(min(-lower.max(), upper.min()))
    if name == "simple":
        return Encoding(name, n, n, 0, phase_hz, lambda a: _simple(n, a, lower, upper))
    if name == "sinusoid":
        return Encoding(name, n, 4, 1, phase_hz, lambda a: _sinusoid(n, a))
    if name == "compound":
        return Encoding(name, n, 9, 2, phase_hz, lambda a: _compound(n, a))
    if name in ("dft", "dft_shift"):
        bins = _check_bins(n, dft_bins)
        # Amplitude budget: bin 0 takes DFT_MEAN_FRACTION of the limit, bins 1..K-1 share the
        # rest; bin k of magnitude |c| adds 2|c| rad, |c| <= sqrt(2)*bound per (re, im) box.
        mean_bound = DFT_MEAN_FRACTION * limit
        wave_bound = (limit - mean_bound) / (2.0 * math.sqrt(2.0) * max(bins - 1, 1))
        scale = np.concatenate(([mean_bound], np.full(2 * (bins - 1), wave_bound)))
        dim = 2 * bins - 1
        low, high = tuple(lower.tolist()), tuple(upper.tolist())
        if name == "dft":
            return Encoding(
                name,
                n,
                dim,
                0,
                phase_hz,
                lambda a: DftGait(n, _coefficients(a, scale), lower_rad=low, upper_rad=high),
            )
        rate = n * phase_hz  # joints/s: one lap of the shape per 1/phase_hz s
        return Encoding(
            name,
            n,
            dim,
            1,
            phase_hz,
            lambda a: DftShiftGait(
                n, _coefficients(a, scale), shift_rate=rate, lower_rad=low, upper_rad=high
            ),
        )
    raise ConfigError(
        "encoding", "", f"unknown encoding {name!r}; expected one of {', '.join(ENCODINGS)}"
    )


def _check_bins(joint_count: int, bins: int) -> int:
    # Bins 0..K-1 must stay below Nyquist (N/2 for even N), the one bin a fractional shift of a
    # real signal cannot represent (its shifted value is complex, and irfft drops the imaginary
    # part): that is how the seed's "rotating DFT" stopped being a shift.
    top = (joint_count - 1) // 2 + 1
    if isinstance(bins, bool) or not isinstance(bins, int) or not 2 <= bins <= top:
        raise ConfigError(
            "dft_bins",
            "",
            f"expected an integer 2..{top} for {joint_count} joints (bins below "
            f"Nyquist, bin 0 included), got {bins!r}",
        )
    return bins


def _coefficients(action: FloatArray, scale: FloatArray) -> tuple[float, ...]:
    values = action * scale
    # Interleaved (re, im) with bin 0's imaginary part 0 (a real mean angle).
    return (float(values[0]), 0.0, *map(float, values[1:]))


def _simple(n: int, action: FloatArray, lower: FloatArray, upper: FloatArray) -> PhasedGait:
    pose = np.where(action >= 0.0, action * upper, -action * lower)
    return SimpleGait(n, tuple(pose.tolist()))


def _sinusoid(n: int, action: FloatArray) -> PhasedGait:
    return SerpenoidGait(
        n,
        amplitude=lerp(action[0], AMPLITUDE_RAD),
        omega=2.0 * math.pi * lerp(action[1], FREQUENCY_HZ),
        phase_lag=lerp(action[2], PHASE_LAG_RAD),
        offset=lerp(action[3], OFFSET_RAD),
    )


def _compound(n: int, action: FloatArray) -> PhasedGait:
    return CompoundGait(
        n,
        amplitude_even=lerp(action[0], AMPLITUDE_RAD),
        amplitude_odd=lerp(action[1], AMPLITUDE_RAD),
        offset_even=lerp(action[2], OFFSET_RAD),
        offset_odd=lerp(action[3], OFFSET_RAD),
        spatial_freq_even=lerp(action[4], SPATIAL_RAD),
        spatial_freq_odd=lerp(action[5], SPATIAL_RAD),
        temporal_freq_even=2.0 * math.pi * lerp(action[6], FREQUENCY_HZ),
        temporal_freq_odd=2.0 * math.pi * lerp(action[7], FREQUENCY_HZ),
        phase_shift=lerp(action[8], PHASE_SHIFT_RAD),
    )


class GaitClock:
    """The phases (P,) in rad that the current gait is played at, integrated step by step.

    Static encodings (P = 0) keep one reference phase turning at ``clock_hz`` instead.
    """

    def __init__(self, encoding: Encoding) -> None:
        self.encoding = encoding
        self.phase_rad = np.zeros(encoding.phase_count)
        self.clock_rad = 0.0

    def reset(self, phase_rad: float = 0.0) -> None:
        """Start every phase (and the reference clock) at ``phase_rad``."""
        self.phase_rad[:] = phase_rad
        self.clock_rad = phase_rad

    def targets(self, gait: PhasedGait) -> FloatArray:
        """Joint targets (N,) in rad of ``gait`` at the current phases."""
        return gait.targets_at_phase(self.phase_rad)

    def advance(self, gait: PhasedGait, dt_s: float) -> None:
        """Turn the phases by the gait's rates over ``dt_s`` s (kept within [0, 2*pi))."""
        if self.phase_rad.size:
            self.phase_rad = np.mod(self.phase_rad + gait.phase_rates_rad_s * dt_s, 2 * math.pi)
        self.clock_rad = (self.clock_rad + 2 * math.pi * self.encoding.clock_hz * dt_s) % (
            2 * math.pi
        )

    def observed(self) -> FloatArray:
        """(sin, cos) of each observed phase, flattened: shape (2 * max(P, 1),)."""
        phases = self.phase_rad if self.phase_rad.size else np.array([self.clock_rad])
        return np.column_stack([np.sin(phases), np.cos(phases)]).ravel()
