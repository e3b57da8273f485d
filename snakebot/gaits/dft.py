"""Frequency-domain pose encodings from "Serpentile Locomotion": DFT and phase-shifted DFT.

Coefficients are interleaved (re, im) pairs for rfft bins 0..K-1, bin 0 (the mean angle)
included, normalised so the inverse needs no 1/N: bin k of magnitude c (0 < k < N/2) adds a
spatial sinusoid of amplitude 2c rad with k waves along the body, whatever N is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
import numpy.typing as npt

from snakebot.errors import GaitError
from snakebot.gaits.base import FloatArray, Gait, PhasedGait, check_finite, check_joint_count
from snakebot.gaits.spec import GaitSpec, LiveRoles, ParamSpec, ParamValues

ComplexArray = npt.NDArray[np.complex128]

DEFAULT_COEFFICIENTS = (0.0, 0.0, 0.0, -0.2)
DEFAULT_LIMIT_RAD = math.pi / 2


def dft_coefficients_from_pose(pose_rad: npt.ArrayLike) -> tuple[float, ...]:
    """Interleaved (re, im) coefficients of all N//2+1 bins that reproduce pose (N,) exactly."""
    pose = np.asarray(pose_rad, dtype=np.float64)
    if pose.ndim != 1 or pose.size == 0:
        raise GaitError(f"dft: expected a pose of shape (N,), got shape {pose.shape}")
    spectrum = np.fft.rfft(pose, norm="forward")
    return tuple(float(v) for v in np.column_stack([spectrum.real, spectrum.imag]).ravel())


def scale_into_limits(
    pose_rad: FloatArray, lower_rad: FloatArray, upper_rad: FloatArray
) -> FloatArray:
    """Scale each pose (..., N) uniformly about 0 just enough to fit [lower, upper] (N,) in rad."""
    if (pose_rad >= lower_rad).all() and (pose_rad <= upper_rad).all():
        return pose_rad.copy()  # the common case, and what the scaling below gives bit for bit
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        room = np.where(
            pose_rad > 0.0,
            upper_rad / pose_rad,
            np.where(pose_rad < 0.0, lower_rad / pose_rad, 1.0),
        )
    factor = np.minimum(1.0, room.min(axis=-1, keepdims=True))
    fitted: FloatArray = np.clip(pose_rad * factor, lower_rad, upper_rad)
    return fitted


@dataclass(frozen=True)
class _FourierPose(PhasedGait):
    """Shared validation and synthesis of the two DFT gaits; limits () mean +-pi/2 rad."""

    gait_name: ClassVar[str] = "dft"

    joint_count: int
    coefficients: tuple[float, ...] = DEFAULT_COEFFICIENTS
    scale: float = 1.0
    lower_rad: tuple[float, ...] = ()
    upper_rad: tuple[float, ...] = ()
    _spectrum: ComplexArray = field(init=False, repr=False, compare=False)
    _lower: FloatArray = field(init=False, repr=False, compare=False)
    _upper: FloatArray = field(init=False, repr=False, compare=False)
    _bins: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        name = self.gait_name
        n = check_joint_count(name, self.joint_count)
        check_finite(name, scale=self.scale)
        values = np.asarray(self.coefficients, dtype=np.float64)
        bins = n // 2 + 1
        if values.ndim != 1 or values.size == 0 or values.size % 2 or values.size > 2 * bins:
            raise GaitError(
                f"{name}.coefficients: expected an even count of 2..{2 * bins} values "
                f"(re, im pairs for at most N//2+1 = {bins} bins), got {values.size}"
            )
        if not np.all(np.isfinite(values)):
            raise GaitError(f"{name}.coefficients: expected finite numbers")
        spectrum = np.zeros(bins, dtype=np.complex128)
        spectrum[: values.size // 2] = values[0::2] + 1j * values[1::2]
        lower = self._limit("lower_rad", self.lower_rad, -DEFAULT_LIMIT_RAD)
        upper = self._limit("upper_rad", self.upper_rad, DEFAULT_LIMIT_RAD)
        bad = np.flatnonzero((lower > 0.0) | (upper < 0.0))
        if bad.size:
            j = int(bad[0])
            raise GaitError(
                f"{name}: joint limits must contain 0 rad (poses are scaled about 0), "
                f"joint {j} has [{lower[j]:g}, {upper[j]:g}]"
            )
        object.__setattr__(self, "_spectrum", spectrum)
        object.__setattr__(self, "_lower", lower)
        object.__setattr__(self, "_upper", upper)
        object.__setattr__(self, "_bins", np.arange(bins, dtype=np.float64))

    @property
    def gait_label(self) -> str:
        """ "dft" or "dft_shift"."""
        return self.gait_name

    def _limit(self, key: str, values: tuple[float, ...], default: float) -> FloatArray:
        if not values:
            return np.full(self.joint_count, default)
        limit = np.asarray(values, dtype=np.float64)
        if limit.shape != (self.joint_count,) or not np.all(np.isfinite(limit)):
            raise GaitError(
                f"{self.gait_name}.{key}: expected {self.joint_count} finite joint limits in rad, "
                f"got {len(values)}"
            )
        return limit

    def _synthesise(self, spectra: ComplexArray) -> FloatArray:
        poses = np.fft.irfft(spectra, n=self.joint_count, norm="forward") * self.scale
        return scale_into_limits(poses, self._lower, self._upper)


@dataclass(frozen=True)
class DftGait(_FourierPose):
    """A static pose (N,) in rad: the inverse real DFT of the coefficients, fitted into limits.

    No phase (P = 0): the same pose at every time.
    """

    gait_name: ClassVar[str] = "dft"

    @property
    def phase_rates_rad_s(self) -> FloatArray:
        """Empty: a static pose."""
        return np.zeros(0)

    _pose: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        # Synthesised once: the pose does not change with time.
        object.__setattr__(self, "_pose", self._synthesise(self._spectrum[None, :]))

    def _at_phases(self, phases: FloatArray) -> FloatArray:
        return np.repeat(self._pose, phases.shape[0], axis=0)


@dataclass(frozen=True)
class DftShiftGait(_FourierPose):
    """The DFT pose shifted toward the tail by D = shift0 + shift_rate*t joints (fractional ok).

    Bin k is multiplied by exp(-2j*pi*k*D/N), so an integer D is np.roll(pose, D). One phase,
    2*pi*D/N rad (a full turn is one lap of the shape along the body).
    """

    gait_name: ClassVar[str] = "dft_shift"

    shift_rate: float = 4.0
    shift0: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        check_finite(self.gait_name, shift_rate=self.shift_rate, shift0=self.shift0)

    @property
    def period_s(self) -> float | None:
        """N/|shift_rate| in s (one full lap of the shape); None when shift_rate is 0."""
        return None if self.shift_rate == 0.0 else self.joint_count / abs(self.shift_rate)

    @property
    def phase_rates_rad_s(self) -> FloatArray:
        """[2*pi*shift_rate/N] in rad/s."""
        return np.array([2.0 * math.pi * self.shift_rate / self.joint_count])

    @property
    def phase0_rad(self) -> FloatArray:
        """[2*pi*shift0/N] in rad."""
        return np.array([2.0 * math.pi * self.shift0 / self.joint_count])

    def _at_phases(self, phases: FloatArray) -> FloatArray:
        rotation = np.exp(-1j * np.outer(phases[:, 0], self._bins))
        return self._synthesise(rotation * self._spectrum[None, :])


_COMMON = (
    ParamSpec(
        "coefficients",
        "rad",
        DEFAULT_COEFFICIENTS,
        "interleaved re,im of rfft bins 0..K-1 (bin 0 = mean angle), K <= N//2+1",
    ),
    ParamSpec("scale", "1", 1.0, "gain on the pose before it is fitted into the joint limits"),
)


def _limits(lower: FloatArray, upper: FloatArray) -> dict[str, tuple[float, ...]]:
    return {"lower_rad": tuple(map(float, lower)), "upper_rad": tuple(map(float, upper))}


def _build_dft(joint_count: int, p: ParamValues, lower: FloatArray, upper: FloatArray) -> Gait:
    return DftGait(
        joint_count, p.numbers("coefficients"), p.number("scale"), **_limits(lower, upper)
    )


def _build_shift(joint_count: int, p: ParamValues, lower: FloatArray, upper: FloatArray) -> Gait:
    return DftShiftGait(
        joint_count,
        p.numbers("coefficients"),
        p.number("scale"),
        shift_rate=p.number("shift_rate"),
        shift0=p.number("shift0"),
        **_limits(lower, upper),
    )


SPECS = (
    GaitSpec(
        name="dft",
        summary=(
            "Static pose from a few DFT coefficients (Serpentile Locomotion); scaled uniformly "
            "into the joint limits when it exceeds them."
        ),
        params=_COMMON,
        factory=_build_dft,
        live=LiveRoles(amplitude=("scale",)),
    ),
    GaitSpec(
        name="dft_shift",
        summary=(
            "Phase-shifted DFT (Serpentile Locomotion): the DFT pose slides toward the tail at "
            "shift_rate joints/s, so constant coefficients make a travelling wave."
        ),
        params=(
            *_COMMON,
            ParamSpec(
                "shift_rate", "joints/s", 4.0, "shift speed; > 0 moves the shape to the tail"
            ),
            ParamSpec("shift0", "joints", 0.0, "shift at t = 0"),
        ),
        factory=_build_shift,
        live=LiveRoles(amplitude=("scale",), frequency=("shift_rate",)),
    ),
)
