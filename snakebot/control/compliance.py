"""Gait-based compliance: the gait's shape gives way where the servos push hard.

After Rollinson et al., "Gait-based compliant control for snake robots" (IROS 2014): instead of
making each joint soft, the measured joint torques are mapped onto a few parameters of the gait
and those parameters, not the joints, behave like a spring-damper. Here the parameters are an
amplitude scale and an offset for each of ``windows`` overlapping Gaussian windows along the
body (head to tail), so the wave flattens and bends away locally, where a peg or a wall holds
it, and springs back to the gait as it was once the push stops:

    target_i(t) = gait_i(t) * (G s)_i + (G o)_i
    ds/dt = -(s - 1) / T - k_s * G^T (gait(t) * e)
    do/dt = -o / T - k_o * G^T e

with ``G`` (N, W) the windows (rows summing to 1), ``e`` the torques beyond a dead band, each as
a fraction of the servo's stall torque (``e_i = sign(tau_i) max(|tau_i|/tau_stall - d, 0)``),
``T`` the return time. A servo's torque pushes its joint towards its command; moving the
parameters against the projected torque moves the command towards where the joint is held,
so the push eases. The dead band keeps the torque of ordinary locomotion (driving the body
against the ground) from bending the gait.

The torque is what the servos measure: a chain whose model has a Present Current register
(torque = kt * current, the torque constant from the servo file), or the twin's servo model
(its output torque, what that register would read). ``check_torque_sensing`` refuses anything
else with a message that says why.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from snakebot.backends.capabilities import SensesTorque
from snakebot.control.cycle import CycleRecord
from snakebot.errors import ConfigError
from snakebot.gaits.base import FloatArray, Gait

__all__ = [
    "ComplianceSettings",
    "CompliantGait",
    "StallMeter",
    "check_torque_sensing",
]

STALL_TORQUE_FRACTION = 0.5
"""A servo counts as stalled while it pushes with at least this fraction of its stall torque ..."""
STALL_SPEED_FRACTION = 0.05
"""... and turns at under this fraction of its no-load speed."""


@dataclass(frozen=True)
class ComplianceSettings:
    """How the gait yields.

    ``windows``: amplitude/offset windows along the body (>= 1). ``dead_band``: torque, as a
    fraction of stall torque, that bends nothing (0..1). ``amplitude_gain`` (1/(s*rad)) and
    ``offset_gain`` (rad/s) per unit of projected torque fraction; ``return_s`` (s): how fast
    the parameters spring back. ``amplitude_range`` bounds the amplitude scales,
    ``offset_limit_rad`` the offsets (rad).
    """

    windows: int = 4
    dead_band: float = 0.3
    amplitude_gain: float = 33.0
    offset_gain: float = 3.3
    return_s: float = 0.3
    amplitude_range: tuple[float, float] = (0.2, 1.5)
    offset_limit_rad: float = 0.5

    def __post_init__(self) -> None:
        checks = (
            ("windows", self.windows >= 1, "at least 1"),
            ("dead_band", 0.0 <= self.dead_band < 1.0, "from 0 to below 1"),
            ("amplitude_gain", self.amplitude_gain >= 0.0, ">= 0"),
            ("offset_gain", self.offset_gain >= 0.0, ">= 0"),
            ("return_s", self.return_s > 0.0, "> 0 s"),
            (
                "amplitude_range",
                0.0 <= self.amplitude_range[0] <= 1.0 <= self.amplitude_range[1],
                "(low, high) with low <= 1 <= high",
            ),
            ("offset_limit_rad", self.offset_limit_rad >= 0.0, ">= 0 rad"),
        )
        for name, ok, expected in checks:
            value = getattr(self, name)
            finite = all(math.isfinite(v) for v in np.atleast_1d(np.asarray(value, dtype=float)))
            if not ok or not finite:
                raise ConfigError("compliance", name, f"expected {expected}, got {value!r}")


def windows_matrix(joint_count: int, windows: int) -> FloatArray:
    """Gaussian windows (N, W) along the body, centres evenly from head to tail, rows sum to 1."""
    count = min(windows, joint_count)
    joints = np.arange(joint_count, dtype=float)
    if count == 1:
        return np.ones((joint_count, 1))
    centres = np.linspace(0.0, joint_count - 1.0, count)
    width = 0.6 * (joint_count - 1.0) / (count - 1)
    weights = np.exp(-0.5 * ((joints[:, None] - centres[None, :]) / width) ** 2)
    matrix: FloatArray = weights / weights.sum(axis=1, keepdims=True)
    return matrix


class CompliantGait(Gait):
    """``gait`` whose amplitude and offset yield, window by window, to the measured torques.

    Targets come from the parameters as they are; ``observe`` (a cycle observer: add it to the
    run's observers) moves them with each cycle's record. ``stall_torque_nm`` is the servos'
    stall torque (N*m). ``reset`` puts the parameters back to the gait as it was.
    """

    def __init__(
        self, gait: Gait, stall_torque_nm: float, settings: ComplianceSettings | None = None
    ) -> None:
        if not (math.isfinite(stall_torque_nm) and stall_torque_nm > 0):
            raise ConfigError(
                "compliance", "stall_torque_nm", f"expected > 0 N*m, got {stall_torque_nm}"
            )
        self.gait = gait
        self.joint_count = gait.joint_count
        self.settings = settings or ComplianceSettings()
        self.stall_torque_nm = float(stall_torque_nm)
        self.windows = windows_matrix(self.joint_count, self.settings.windows)
        count = self.windows.shape[1]
        self.amplitude_scale = np.ones(count)
        """Each window's amplitude scale now (W,), 1 = the gait's own."""
        self.offset_rad = np.zeros(count)
        """Each window's offset now (W,) rad, 0 = the gait's own."""
        self.lowest_scale = np.ones(count)
        """The smallest amplitude scale each window reached (W,)."""
        self.largest_offset_rad = np.zeros(count)
        """The largest |offset| each window reached (W,) rad."""
        self._raw: FloatArray | None = None

    @property
    def period_s(self) -> float | None:
        """The wrapped gait's period, s."""
        return self.gait.period_s

    @property
    def uses_measured_pose(self) -> bool:
        """True: the targets follow what the servos measure, never computed ahead."""
        return True  # its targets follow what the servos measured: never computed ahead

    def _shaped(self, raw: FloatArray) -> FloatArray:
        shaped: FloatArray = raw * (self.windows @ self.amplitude_scale)
        shaped += self.windows @ self.offset_rad
        return shaped

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        """The gait's targets (rad, (N,) or (T, N)) with the parameters as they are now."""
        return self._shaped(self.gait.targets(time_s))

    def command(self, time_s: float, measured_rad: FloatArray | None = None) -> FloatArray:
        """One cycle's targets (N,) rad; remembers the gait's own for the next ``observe``."""
        raw = self.gait.command(time_s, measured_rad)
        self._raw = raw
        return self._shaped(raw)

    def observe(self, record: CycleRecord) -> None:
        """Move the parameters by the cycle's measured torques over its period."""
        raw = self._raw
        if raw is None or not record.period_s > 0:
            return
        s = self.settings
        fraction = record.state.effort_nm / self.stall_torque_nm
        excess = np.sign(fraction) * np.maximum(np.abs(fraction) - s.dead_band, 0.0)
        on_scale = self.windows.T @ (raw * excess)
        on_offset = self.windows.T @ excess
        dt = record.period_s
        spring = (self.amplitude_scale - 1.0) / s.return_s
        self.amplitude_scale += dt * (-spring - s.amplitude_gain * on_scale)
        self.offset_rad += dt * (-self.offset_rad / s.return_s - s.offset_gain * on_offset)
        np.clip(self.amplitude_scale, *s.amplitude_range, out=self.amplitude_scale)
        np.clip(self.offset_rad, -s.offset_limit_rad, s.offset_limit_rad, out=self.offset_rad)
        np.minimum(self.lowest_scale, self.amplitude_scale, out=self.lowest_scale)
        np.maximum(self.largest_offset_rad, np.abs(self.offset_rad), out=self.largest_offset_rad)

    def reset(self) -> None:
        """The wrapped gait reset, the parameters back to the gait as it was."""
        self.gait.reset()
        self.amplitude_scale[:] = 1.0
        self.offset_rad[:] = 0.0
        self.lowest_scale[:] = 1.0
        self.largest_offset_rad[:] = 0.0
        self._raw = None

    def summary(self) -> dict[str, object]:
        """JSON-ready: the settings and how far each window yielded."""
        return {
            "windows": self.windows.shape[1],
            "dead_band": self.settings.dead_band,
            "lowest_amplitude_scale": [round(float(v), 4) for v in self.lowest_scale],
            "largest_offset_rad": [round(float(v), 4) for v in self.largest_offset_rad],
        }


class StallMeter:
    """A cycle observer: how long the servos pushed hard without moving, and the peak torque.

    A servo is stalled in a cycle while ``|torque| >= STALL_TORQUE_FRACTION * stall_torque_nm``
    and ``|speed| < STALL_SPEED_FRACTION * no_load_speed_rad_s``; ``stall_s`` sums those cycles'
    periods over every servo (servo-seconds). Only scored cycles (the gait, not the ramps) count.
    """

    def __init__(self, stall_torque_nm: float, no_load_speed_rad_s: float) -> None:
        self.torque_nm = STALL_TORQUE_FRACTION * stall_torque_nm
        self.speed_rad_s = STALL_SPEED_FRACTION * no_load_speed_rad_s
        self.stall_s = 0.0
        self.peak_torque_nm = 0.0

    def __call__(self, record: CycleRecord) -> None:
        """Count one cycle's record."""
        if not record.scored:
            return
        effort = np.abs(record.state.effort_nm)
        still = np.abs(record.state.velocity_rad_s) < self.speed_rad_s
        stalled = (effort >= self.torque_nm) & still
        self.stall_s += float(np.count_nonzero(stalled)) * record.period_s
        self.peak_torque_nm = max(self.peak_torque_nm, float(effort.max(initial=0.0)))

    def summary(self) -> dict[str, float]:
        """``servo_stall_s`` and ``peak_servo_torque_nm``."""
        return {"servo_stall_s": self.stall_s, "peak_servo_torque_nm": self.peak_torque_nm}


def check_torque_sensing(backend: object, where: str = "compliance", servo: str = "") -> None:
    """Raise ConfigError (naming ``where``, and the servo model ``servo`` when given) unless
    ``backend`` measures its joints' torque (``SensesTorque``)."""
    if isinstance(backend, SensesTorque):
        return
    what = f"{type(backend).__name__}" + (f" with {servo} servos" if servo else "")
    raise ConfigError(
        where,
        "",
        f"compliance yields to the torque the servos measure, and {what} does not measure "
        "it: on servos it needs a model with a Present Current register (e.g. XM430, XL330, "
        "MX-64 2.0, Feetech STS3215; XL430 and AX report only a load estimate), and the rigid "
        "twin models it",
    )
