"""The gait interface: joint targets (rad) as a pure function of time (s), plus a feedback hook.

Periodic gaits are also functions of explicit temporal phases (``PhasedGait``): ``targets(t)`` is
``targets_at_phase(phase0 + rates * t)``, one formula, so a live driver can integrate the phases
cycle by cycle and change the frequency without the targets jumping.
"""

from __future__ import annotations

import abc
import math

import numpy as np
import numpy.typing as npt

from snakebot.errors import GaitError

FloatArray = npt.NDArray[np.float64]


class Gait(abc.ABC):
    """A joint-space gait for an N-joint snake, joints indexed head (0) to tail (N-1)."""

    joint_count: int

    @property
    def period_s(self) -> float | None:
        """One gait cycle in s, or None when the gait is static or not periodic."""
        return None

    @abc.abstractmethod
    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        """Joint targets in rad: scalar time -> shape (N,), times of shape (T,) -> shape (T, N)."""

    def command(self, time_s: float, measured_rad: FloatArray | None = None) -> FloatArray:
        """Targets (N,) in rad for one control cycle; feedback gaits may use the measured pose."""
        return self.targets(time_s)

    @property
    def uses_measured_pose(self) -> bool:
        """True when command() reads measured_rad (closed loop), so commands cannot be computed
        ahead of the run. By default a gait that overrides command() is taken to use it; such a
        gait overrides this property when it knows better (keyframes advanced by time)."""
        return type(self).command is not Gait.command

    def reset(self) -> None:
        """Forget any internal state so the next command starts the gait afresh."""
        return None


def as_times(gait: str, time_s: float | npt.ArrayLike) -> tuple[FloatArray, bool]:
    """Times as a 1-D float array (T,) in s, and whether the caller passed a scalar."""
    if type(time_s) is float and math.isfinite(time_s):  # the control loop's case, once a cycle
        return np.array([time_s]), True
    try:
        t = np.asarray(time_s, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise GaitError(f"{gait}: time_s must be a number or 1-D array of s ({exc})") from exc
    if t.ndim > 1:
        raise GaitError(f"{gait}: time_s must be a scalar or a 1-D array (T,), got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise GaitError(f"{gait}: time_s must be finite, got {time_s!r}")
    return np.atleast_1d(t), t.ndim == 0


def shaped(values: FloatArray, scalar: bool) -> FloatArray:
    """Return (T, N) targets as they are, or row 0 (N,) when the caller passed a scalar time."""
    return values[0].copy() if scalar else values


def check_joint_count(gait: str, joint_count: object) -> int:
    """Validate N (a positive int) so every gait fails the same way on a bad joint count."""
    if isinstance(joint_count, bool) or not isinstance(joint_count, int | np.integer):
        raise GaitError(f"{gait}: joint_count must be a positive integer, got {joint_count!r}")
    if joint_count < 1:
        raise GaitError(f"{gait}: joint_count must be at least 1, got {joint_count}")
    return int(joint_count)


def check_finite(gait: str, **values: float) -> None:
    """Reject NaN or infinite scalar parameters, naming the first offending one."""
    for name, value in values.items():
        if not math.isfinite(value):
            raise GaitError(f"{gait}.{name}: expected a finite number, got {value!r}")


class PhasedGait(Gait):
    """A gait whose targets are a function of P temporal phases in rad (P may be 0: static).

    ``targets(t) = targets_at_phase(phase0_rad + phase_rates_rad_s * t)``. Subclasses provide
    ``phase_rates_rad_s`` (P,), optionally ``phase0_rad`` (P,), and ``_at_phases`` on (T, P).
    """

    @property
    @abc.abstractmethod
    def phase_rates_rad_s(self) -> FloatArray:
        """How fast each phase turns, shape (P,) in rad/s (P = 0 for a static pose)."""

    @property
    def phase0_rad(self) -> FloatArray:
        """The phases (P,) in rad at t = 0."""
        return np.zeros(self.phase_rates_rad_s.size)

    @property
    def gait_label(self) -> str:
        """The name errors start with."""
        return type(self).__name__

    @abc.abstractmethod
    def _at_phases(self, phases: FloatArray) -> FloatArray:
        """Targets (T, N) in rad for phases (T, P) in rad; the one formula of the gait."""

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        """Joint angles in rad: (N,) for a scalar time in s, (T, N) for times (T,)."""
        if type(time_s) is float and math.isfinite(time_s):  # the control loop's case
            return self._at_time(time_s)
        t, scalar = as_times(self.gait_label, time_s)
        phases = self.phase0_rad + t[:, None] * self.phase_rates_rad_s
        return shaped(self._at_phases(phases), scalar)

    def _at_time(self, time_s: float) -> FloatArray:
        """Targets (N,) in rad at one finite time in s, once a control cycle: the floats of
        ``targets`` at times (T,). A gait may override it with fewer numpy calls that give the
        same bits (tests/unit/gaits hold each to its array path)."""
        row = self.phase0_rad + time_s * self.phase_rates_rad_s  # the same floats as (T,)
        return shaped(self._at_phases(row[None, :]), True)

    def targets_at_phase(self, phase_rad: npt.ArrayLike) -> FloatArray:
        """Joint angles in rad at explicit phases: (P,) -> (N,), (T, P) -> (T, N).

        Raises GaitError when the phases are not finite or not P per row.
        """
        count = self.phase_rates_rad_s.size
        try:
            phases = np.asarray(phase_rad, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise GaitError(f"{self.gait_label}: phases must be numbers in rad ({exc})") from exc
        if phases.ndim not in (1, 2) or phases.shape[-1] != count:
            raise GaitError(
                f"{self.gait_label}: expected phases of shape ({count},) or (T, {count}) in rad, "
                f"got shape {phases.shape}"
            )
        if not np.isfinite(phases).all():
            raise GaitError(f"{self.gait_label}: phases must be finite")
        return shaped(self._at_phases(np.atleast_2d(phases)), phases.ndim == 1)
