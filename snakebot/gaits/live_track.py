"""One gait playing live: integrated phases and smoothed controls (speed, turn, amplitude, wave).

A ``TrackModel`` turns the drive controls into gait parameters through the gait's ``LiveRoles``;
a ``Track`` is one moment of a gait playing: its phases (rad), the controls it has reached and the
gait built for them. ``Track.advanced(dt)`` integrates the phases at the current speed, so a
frequency or direction change turns the phase faster or backwards and never jumps a target.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from snakebot.errors import GaitError
from snakebot.gaits.base import FloatArray, Gait, PhasedGait
from snakebot.gaits.spec import GaitSpec, ParamValue, ParamValues

DEFAULT_TURN_RAD = 0.3
"""Offset at full turn for gaits that declare no offset parameter (added on the steer joints)."""
DEFAULT_SPEED_CAP = 4.0
"""Fastest speed (a multiple of the gait's own frequency) when its frequency has no bounds."""
DEFAULT_AMPLITUDE_CAP = 2.0
"""Largest amplitude multiple when the gait's amplitude parameters have no bounds."""
_PHASE_SAMPLES = 96


@dataclass(frozen=True)
class TimeWarpedGait(PhasedGait):
    """Any gait of time alone seen as one phase, 2*pi*t/period (t in s for an aperiodic gait),
    so gaits written before phases (plugins) drive live too: speed warps their time."""

    inner: Gait

    def __post_init__(self) -> None:
        object.__setattr__(self, "joint_count", self.inner.joint_count)

    @property
    def gait_label(self) -> str:
        """The wrapped gait's class name."""
        return type(self.inner).__name__

    @property
    def period_s(self) -> float | None:
        """The wrapped gait's period."""
        return self.inner.period_s

    @property
    def phase_rates_rad_s(self) -> FloatArray:
        """[2*pi/period] in rad/s, or [1] (one rad of phase per s) without a period."""
        period = self.inner.period_s
        return np.array([2.0 * math.pi / period if period else 1.0])

    def _at_phases(self, phases: FloatArray) -> FloatArray:
        times = phases[:, 0] / self.phase_rates_rad_s[0]
        return np.asarray(self.inner.targets(times), dtype=np.float64).reshape(len(times), -1)


@dataclass(frozen=True)
class LiveControls:
    """What a driver asks of a live gait; all are multiples or fractions, not units.

    ``speed``: multiple of the gait's own temporal frequency (1 = as configured, 0 = frozen,
    < 0 = backwards). ``turn``: -1..1 of the steering offset's range; > 0 turns left
    (counter-clockwise seen from above) while the gait moves head first, by biasing the
    steering joints negative: a yaw joint's positive angle turns the tail-side link about +z,
    which curls the body into a right-hand turn (measured on the twin). Backwards, the same
    curl turns the other way, as a car's steering does. ``amplitude``: multiple of the
    configured amplitude. ``wavelength``: multiple of the configured wavelength (the spatial
    frequency is divided by it).
    """

    speed: float = 0.0
    turn: float = 0.0
    amplitude: float = 1.0
    wavelength: float = 1.0

    def approach(self, target: LiveControls, step: float) -> LiveControls:
        """Each control moved toward ``target`` by at most ``step`` (a rate limit)."""
        return LiveControls(
            *(
                value + min(max(goal - value, -step), step)
                for value, goal in zip(self.astuple(), target.astuple(), strict=True)
            )
        )

    def astuple(self) -> tuple[float, float, float, float]:
        """(speed, turn, amplitude, wavelength)."""
        return (self.speed, self.turn, self.amplitude, self.wavelength)


@dataclass(frozen=True)
class ControlBounds:
    """The range of each control for one gait on one robot (closed intervals)."""

    speed: tuple[float, float]
    turn: tuple[float, float]
    amplitude: tuple[float, float]
    wavelength: tuple[float, float]

    def clip(self, controls: LiveControls) -> LiveControls:
        """``controls`` with every value clipped into its range."""
        ranges = (self.speed, self.turn, self.amplitude, self.wavelength)
        return LiveControls(
            *(
                float(min(max(v, low), high))
                for v, (low, high) in zip(controls.astuple(), ranges, strict=True)
            )
        )


@dataclass(frozen=True)
class TrackModel:
    """How the controls of one gait become its parameters, and the controls' bounds.

    ``nominal`` are the gait's resolved parameters; ``steer`` (N,) weights where a gait without
    an offset parameter takes the turn bias (1 on yaw joints); ``lower``/``upper`` (N,) rad are
    the joint limits; ``smoothing_s`` is how long a change of one unit of a control takes.
    """

    spec: GaitSpec
    nominal: Mapping[str, ParamValue]
    joint_count: int
    lower: FloatArray
    upper: FloatArray
    steer: FloatArray
    smoothing_s: float
    bounds: ControlBounds = field(init=False)
    _peaks: dict[tuple[float, ...], float] = field(
        init=False, repr=False, compare=False, default_factory=dict
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "bounds", self._bounds())

    @property
    def name(self) -> str:
        """The gait's name."""
        return self.spec.name

    def build(self, controls: LiveControls) -> PhasedGait:
        """The gait with the parameters ``controls`` ask for. Raises GaitError if not phased."""
        roles = self.spec.live
        params = dict(self.nominal)
        for key in roles.amplitude:
            params[key] = self._number(key) * controls.amplitude
        for key in roles.spatial_frequency:
            params[key] = self._number(key) / controls.wavelength
        for key in roles.offset:
            low, high = self._offset_range(key)
            nominal = self._number(key)
            span = nominal - low if controls.turn > 0 else high - nominal
            params[key] = nominal - controls.turn * span
        gait = self.spec.factory(
            self.joint_count, ParamValues(self.name, params), self.lower, self.upper
        )
        if gait.uses_measured_pose:
            raise GaitError(
                f"{self.name}: cannot be driven live: it reads the measured pose, so its "
                "targets are no function of a phase (keyframes: use advance=time)"
            )
        return gait if isinstance(gait, PhasedGait) else TimeWarpedGait(gait)

    def param_key(self, controls: LiveControls) -> tuple[float, ...]:
        """The controls that change the gait's parameters (equal keys give the same gait)."""
        roles = self.spec.live
        return (
            controls.amplitude if roles.amplitude else 1.0,
            controls.wavelength if roles.spatial_frequency else 1.0,
            controls.turn if roles.offset else 0.0,
        )

    def finish(self, targets: FloatArray, controls: LiveControls) -> FloatArray:
        """Apply the controls a gait has no parameter for (generic amplitude and turn)."""
        roles = self.spec.live
        if not roles.amplitude:
            targets = targets * controls.amplitude
        if not roles.offset:
            targets = targets - controls.turn * DEFAULT_TURN_RAD * self.steer
        return targets

    def peak_speed_rad_s(self, controls: LiveControls) -> float:
        """Fastest joint speed in rad/s over one cycle at speed 1 with these controls (the
        speed control is ignored); remembered per shape, as key presses ask it again."""
        key = (*self.param_key(controls), controls.amplitude, controls.turn)
        peak = self._peaks.get(key)
        if peak is None:
            peak = self._peak_speed(controls)
            if len(self._peaks) > 256:
                self._peaks.clear()
            self._peaks[key] = peak
        return peak

    def _peak_speed(self, controls: LiveControls) -> float:
        gait = self.build(controls)
        rates = gait.phase_rates_rad_s
        if rates.size == 0 or not np.any(rates):
            return 0.0
        period = 2.0 * math.pi / float(np.max(np.abs(rates)))
        times = np.linspace(0.0, period, _PHASE_SAMPLES + 1)
        poses = self.finish(gait.targets_at_phase(times[:, None] * rates), controls)
        return float(np.max(np.abs(np.diff(poses, axis=0))) / (times[1] - times[0]))

    def _number(self, key: str) -> float:
        value = self.nominal[key]
        assert isinstance(value, float)
        return value

    def _offset_range(self, key: str) -> tuple[float, float]:
        bounds = self.spec.param(key).bounds
        return bounds if bounds is not None else (-DEFAULT_TURN_RAD, DEFAULT_TURN_RAD)

    def _bounds(self) -> ControlBounds:
        roles = self.spec.live
        gait = self.build(LiveControls())
        speed_cap = DEFAULT_SPEED_CAP if np.any(gait.phase_rates_rad_s) else 0.0
        speed_cap = min([speed_cap, *self._ratios(roles.frequency, upper=True)])
        amplitude = min([DEFAULT_AMPLITUDE_CAP, *self._ratios(roles.amplitude, upper=True)])
        longest = min([math.inf, *(1.0 / r for r in self._ratios(roles.spatial_frequency, False))])
        shortest = max([0.0, *(1.0 / r for r in self._ratios(roles.spatial_frequency, True))])
        wavelength = (shortest, longest) if roles.spatial_frequency else (1.0, 1.0)
        if not math.isfinite(wavelength[1]) or wavelength[0] <= 0.0:
            wavelength = (1.0, 1.0)  # a zero spatial frequency (rolling): no wave to stretch
        return ControlBounds(
            speed=(-speed_cap, speed_cap),
            turn=(-1.0, 1.0),
            amplitude=(0.0, amplitude),
            wavelength=(min(wavelength[0], 1.0), max(wavelength[1], 1.0)),
        )

    def _ratios(self, keys: tuple[str, ...], upper: bool) -> list[float]:
        """bound / |nominal| of each parameter with bounds and a nonzero nominal value."""
        out = []
        for key in keys:
            bounds, nominal = self.spec.param(key).bounds, abs(self._number(key))
            if bounds is not None and nominal > 0.0:
                out.append(max(abs(bounds[1] if upper else bounds[0]), 1e-9) / nominal)
        return out


@dataclass(frozen=True)
class Track:
    """One gait playing: phases (P,) in rad, the controls reached, the gait built for them."""

    model: TrackModel
    phases: FloatArray
    controls: LiveControls
    gait: PhasedGait

    @classmethod
    def start(cls, model: TrackModel, controls: LiveControls, near: FloatArray) -> Track:
        """The gait at ``controls``, at the phase of its cycle whose pose is closest to
        ``near`` (N,) rad, so a blend toward it has the least way to go."""
        gait = model.build(controls)
        rates = gait.phase_rates_rad_s
        if rates.size == 0 or not np.any(rates):
            return cls(model, gait.phase0_rad.copy(), controls, gait)
        period = 2.0 * math.pi / float(np.max(np.abs(rates)))
        phases = np.linspace(0.0, period, _PHASE_SAMPLES, endpoint=False)[:, None] * rates
        poses = model.finish(gait.targets_at_phase(phases), controls)
        best = int(np.argmin(np.max(np.abs(poses - near), axis=1)))
        return cls(model, phases[best].copy(), controls, gait)

    def advanced(self, dt_s: float, setpoint: LiveControls | None) -> Track:
        """This track ``dt_s`` later, its controls moved toward ``setpoint`` (None: kept)."""
        controls = self.controls
        if setpoint is not None and setpoint != controls:
            step = dt_s / self.model.smoothing_s if self.model.smoothing_s > 0 else math.inf
            controls = controls.approach(self.model.bounds.clip(setpoint), step)
        gait = self.gait
        if self.model.param_key(controls) != self.model.param_key(self.controls):
            gait = self.model.build(controls)
        speed = 0.5 * (self.controls.speed + controls.speed)  # trapezoid: exact for a ramp
        phases = self.phases + speed * gait.phase_rates_rad_s * dt_s
        return Track(self.model, phases, controls, gait)

    def pose(self) -> FloatArray:
        """Targets (N,) in rad now (not yet clipped to the joint limits)."""
        return self.model.finish(self.gait.targets_at_phase(self.phases), self.controls)

    def peak_speed_rad_s(self) -> float:
        """Fastest joint speed of this track as it plays now, in rad/s."""
        return abs(self.controls.speed) * self.model.peak_speed_rad_s(self.controls)
