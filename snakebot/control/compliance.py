"""Gait-based compliance: the gait's shape gives way where the servos push hard.

After Rollinson et al., "Gait-based compliant control for snake robots" (IROS 2014): instead of
making each joint soft, the measured joint torques are mapped onto a few parameters of the gait
and those parameters, not the joints, behave like a spring-damper. Here the parameters are an
amplitude scale and an offset for each of ``windows`` overlapping Gaussian windows along the
body (head to tail), and a phase for each window, so the wave flattens, bends away and runs
early or late locally, where a peg or a wall holds it, and springs back to the gait as it was
once the push stops:

    target_i(t) = gait_i(t + delta_i) * (G s)_i + (G o)_i,   delta = G phi * P / (2 pi)
    ds/dt   = -(s - 1) / T - k_s   * G^T (gait(t + delta) * e)
    do/dt   = -o / T       - k_o   * G^T e
    dphi/dt = -phi / T     - k_phi * G^T (gait'(t + delta) * e)

with ``G`` (N, W) the windows (rows summing to 1), ``e`` the torques beyond a dead band, each as
a fraction of the servo's stall torque (``e_i = sign(tau_i) max(|tau_i|/tau_stall - d, 0)``),
``T`` the return time. ``phi`` (rad) is a phase of the gait's cycle of period ``P`` (s), so
joint ``i`` plays the gait ``delta_i`` s early; ``gait' = d gait / d(phase) = gait_dot * P/(2 pi)``
(rad per rad, from a central difference in time), the change of the target per unit of phase,
as ``gait`` is per unit of amplitude scale and 1 per unit of offset. A servo's torque pushes
its joint towards its command; moving each parameter against the torque projected on its own
derivative moves the command towards where the joint is held, so the push eases. The dead band
keeps the torque of ordinary locomotion (driving the body against the ground) from bending the
gait.

Only a gait that is a function of time can be played early or late: one whose
``uses_measured_pose`` is true (its targets follow the servos: keyframes advanced on error, a
policy, a live driver) or whose ``period_s`` is None keeps its phase at 0, and only its
amplitude and offset yield. The phase is off by default (``phase_gain`` 0): swept over 15 of
the twin's peg fields, no gain (1 to 3) helped reliably, and some slowed the XM430 snake to a
crawl on a layout that does not jam (docs/compliance.md).

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

    ``windows``: amplitude/offset/phase windows along the body (>= 1). ``dead_band``: torque,
    as a fraction of stall torque, that bends nothing (0..1). ``amplitude_gain`` (1/(s*rad)),
    ``offset_gain`` (rad/s) and ``phase_gain`` (1/s: rad of phase per s per rad-per-rad of
    projected torque fraction) per unit of projected torque fraction; 0 turns that parameter
    off. ``return_s`` (s): how fast the parameters spring back. ``amplitude_range`` bounds the
    amplitude scales, ``offset_limit_rad`` the offsets (rad), ``phase_limit_rad`` the phases
    (rad of the gait's cycle, at most pi: half a cycle). A bad value raises ConfigError
    naming the field.
    """

    windows: int = 4
    dead_band: float = 0.3
    amplitude_gain: float = 33.0
    offset_gain: float = 3.3
    return_s: float = 0.3
    amplitude_range: tuple[float, float] = (0.2, 1.5)
    offset_limit_rad: float = 0.5
    phase_gain: float = 0.0
    phase_limit_rad: float = math.pi / 4

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
            ("phase_gain", self.phase_gain >= 0.0, ">= 0"),
            ("phase_limit_rad", 0.0 <= self.phase_limit_rad <= math.pi, "from 0 to pi rad"),
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
    """``gait`` whose amplitude, offset and phase yield, window by window, to the measured
    torques.

    Targets come from the parameters as they are; ``observe`` (a cycle observer: add it to the
    run's observers) moves them with each cycle's record. ``stall_torque_nm`` is the servos'
    stall torque (N*m); ConfigError when it is not > 0. ``reset`` puts the parameters back to
    the gait as it was. ``shifts_phase`` says whether the phase can move at all (a gait of time
    with a period, and ``phase_gain`` > 0); otherwise it stays 0.
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
        period = gait.period_s
        self.shifts_phase = bool(
            self.settings.phase_gain > 0.0
            and not gait.uses_measured_pose
            and period is not None
            and math.isfinite(period)
            and period > 0.0
        )
        """True when the phase can move: the gait is a function of time with a period."""
        self._seconds_per_rad = (period or 0.0) / (2.0 * math.pi) if self.shifts_phase else 0.0
        self.amplitude_scale = np.ones(count)
        """Each window's amplitude scale now (W,), 1 = the gait's own."""
        self.offset_rad = np.zeros(count)
        """Each window's offset now (W,) rad, 0 = the gait's own."""
        self.phase_rad = np.zeros(count)
        """Each window's phase now (W,), rad of the gait's cycle, > 0 = early, 0 = the gait's."""
        self.lowest_scale = np.ones(count)
        """The smallest amplitude scale each window reached (W,)."""
        self.largest_offset_rad = np.zeros(count)
        """The largest |offset| each window reached (W,) rad."""
        self.largest_phase_rad = np.zeros(count)
        """The largest |phase| each window reached (W,) rad."""
        self._raw: FloatArray | None = None
        self._shifted_s: FloatArray | None = None  # each joint's gait time at the last command

    @property
    def period_s(self) -> float | None:
        """The wrapped gait's period, s."""
        return self.gait.period_s

    @property
    def uses_measured_pose(self) -> bool:
        """True: the targets follow what the servos measure, never computed ahead."""
        return True  # its targets follow what the servos measured: never computed ahead

    def shift_s(self) -> FloatArray:
        """Each joint's time shift now (N,) s: it plays the gait this much early."""
        shift: FloatArray = (self.windows @ self.phase_rad) * self._seconds_per_rad
        return shift

    def _shaped(self, raw: FloatArray) -> FloatArray:
        shaped: FloatArray = raw * (self.windows @ self.amplitude_scale)
        shaped += self.windows @ self.offset_rad
        return shaped

    def _diagonal(self, joint_times_s: FloatArray) -> FloatArray:
        """The gait at each joint's own time: ``gait_i(joint_times_s[i])`` (N,) rad."""
        everything = self.gait.targets(joint_times_s)  # (N, N): all joints at every time
        diagonal: FloatArray = np.diagonal(everything).copy()
        return diagonal

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        """The gait's targets (rad, (N,) or (T, N)) with the parameters as they are now.

        Raises what the wrapped gait's ``targets`` raises (GaitError for bad times)."""
        if not self.phase_rad.any():
            return self._shaped(self.gait.targets(time_s))
        shift = self.shift_s()
        times = np.asarray(time_s, dtype=np.float64)
        if times.ndim == 0:
            return self._shaped(self._diagonal(float(times) + shift))
        columns = [self.gait.targets(times + shift[i])[:, i] for i in range(self.joint_count)]
        return self._shaped(np.stack(columns, axis=-1))

    def command(self, time_s: float, measured_rad: FloatArray | None = None) -> FloatArray:
        """One cycle's targets (N,) rad; remembers the gait's own for the next ``observe``.

        With every phase at 0 it is the wrapped gait's ``command``, as the gait would play it."""
        if self.phase_rad.any():
            self._shifted_s = float(time_s) + self.shift_s()
            raw = self._diagonal(self._shifted_s)
        else:
            self._shifted_s = np.full(self.joint_count, float(time_s))
            raw = self.gait.command(time_s, measured_rad)
        self._raw = raw
        return self._shaped(raw)

    def _phase_slope(self, joint_times_s: FloatArray) -> FloatArray:
        """d gait_i / d(phase) at each joint's own time (N,), rad per rad of phase: the gait's
        time derivative (a central difference) times P / (2 pi)."""
        step = 1e-3 * self._seconds_per_rad  # 1 mrad of phase, in s
        both = self.gait.targets(np.concatenate([joint_times_s + step, joint_times_s - step]))
        n = self.joint_count
        slope: FloatArray = (np.diagonal(both[:n]) - np.diagonal(both[n:])) / 2e-3
        return slope

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
        if self.shifts_phase and self._shifted_s is not None:
            push = -self.phase_rad / s.return_s
            if excess.any():
                on_phase = self.windows.T @ (self._phase_slope(self._shifted_s) * excess)
                push -= s.phase_gain * on_phase
            self.phase_rad += dt * push
            limit = s.phase_limit_rad
            np.clip(self.phase_rad, -limit, limit, out=self.phase_rad)
            np.maximum(self.largest_phase_rad, np.abs(self.phase_rad), out=self.largest_phase_rad)

    def reset(self) -> None:
        """The wrapped gait reset, the parameters back to the gait as it was."""
        self.gait.reset()
        self.amplitude_scale[:] = 1.0
        self.offset_rad[:] = 0.0
        self.phase_rad[:] = 0.0
        self.lowest_scale[:] = 1.0
        self.largest_offset_rad[:] = 0.0
        self.largest_phase_rad[:] = 0.0
        self._raw = None
        self._shifted_s = None

    def summary(self) -> dict[str, object]:
        """JSON-ready: the settings and how far each window yielded."""
        return {
            "windows": self.windows.shape[1],
            "dead_band": self.settings.dead_band,
            "lowest_amplitude_scale": [round(float(v), 4) for v in self.lowest_scale],
            "largest_offset_rad": [round(float(v), 4) for v in self.largest_offset_rad],
            "largest_phase_rad": [round(float(v), 4) for v in self.largest_phase_rad],
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
