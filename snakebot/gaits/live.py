"""A gait driven live: speed, turn, amplitude and wavelength change mid-run, gaits switch, and no
joint target ever jumps.

``LiveGait`` integrates each gait's temporal phases cycle by cycle (``PhasedGait``), rate-limits
the controls toward their set points over ``smoothing_s`` per unit, blends from one gait to the
next (``transition``) and pauses or stops through the rest pose. Its own governor keeps the step
between consecutive targets under ``margin`` of the servo's speed times the control period: when
a step would be larger, the gait's time runs slower for that cycle. The safety layer's slew limit
downstream is then never what catches a jump.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
import numpy.typing as npt

from snakebot.errors import GaitError
from snakebot.gaits.base import FloatArray, Gait
from snakebot.gaits.live_track import ControlBounds, LiveControls, Track, TrackModel
from snakebot.gaits.registry import get_spec, resolve_params
from snakebot.gaits.transition import Hold, Source, blend_into, newest_blend, newest_track

Mode = Literal["driving", "paused", "stopping"]
_GOVERNOR_TRIES = 6


@dataclass(frozen=True)
class LiveStatus:
    """A snapshot of a live gait for displays and telemetry.

    ``gait`` is the gait driven (or resumed after a pause); ``blend`` the fraction 0..1 of a
    transition under way (None when there is none) and ``blend_left_s`` the time it still takes
    (0 when none); ``speed_limit`` the fastest speed the
    bounds and the servos allow at the set amplitude; ``phase_rad`` the driven gait's phases
    (empty while holding a pose); ``governed_cycles`` counts cycles whose time the governor
    slowed to keep a step within the budget.
    """

    gait: str
    mode: Mode
    setpoint: LiveControls
    controls: LiveControls | None
    bounds: ControlBounds | None
    speed_limit: float
    blend: float | None
    blend_left_s: float
    phase_rad: tuple[float, ...]
    governed_cycles: int
    finished: bool


class LiveGait(Gait):
    """Joint targets (N,) in rad for a snake driven live; advanced by ``command(time_s)``.

    ``lower_rad``/``upper_rad`` (N,) are the joint limits, ``max_speed_rad_s`` the servo speed
    and ``period_s`` the control period the safety layer slew-limits with: every target is within
    ``margin * max_speed_rad_s * period_s`` of the previous one. ``steer`` (N,) weights where a
    gait without an offset parameter puts the turn bias (default: every joint). ``rest_rad``
    (N,) is the pose pause and stop go to (default straight, clipped into the limits).
    ``smoothing_s``: time for a control to move one unit; ``transition_s``: shortest blend.
    Raises GaitError for inconsistent shapes or non-positive times.
    """

    def __init__(
        self,
        joint_count: int,
        *,
        lower_rad: npt.ArrayLike,
        upper_rad: npt.ArrayLike,
        max_speed_rad_s: float,
        period_s: float,
        steer: npt.ArrayLike | None = None,
        rest_rad: npt.ArrayLike | None = None,
        smoothing_s: float = 0.5,
        transition_s: float = 1.0,
        margin: float = 0.8,
    ) -> None:
        self.joint_count = joint_count
        self.lower = self._vector("lower_rad", lower_rad)
        self.upper = self._vector("upper_rad", upper_rad)
        self.steer = self._vector("steer", 1.0 if steer is None else steer)
        rest = self._vector("rest_rad", 0.0 if rest_rad is None else rest_rad)
        self.rest = np.clip(rest, self.lower, self.upper)
        for key, value in (("max_speed_rad_s", max_speed_rad_s), ("period_s", period_s)):
            if not (value > 0 and math.isfinite(value)):
                raise GaitError(f"live gait: {key} must be a positive number, got {value!r}")
        if not (0.0 < margin <= 1.0) or smoothing_s < 0 or transition_s < 0:
            raise GaitError(
                "live gait: expected 0 < margin <= 1 and smoothing_s, transition_s >= 0 s, got "
                f"{margin!r}, {smoothing_s!r}, {transition_s!r}"
            )
        self.control_period_s = float(period_s)
        self.speed_budget_rad_s = margin * float(max_speed_rad_s)
        self.smoothing_s = float(smoothing_s)
        self.transition_s = float(transition_s)
        self._gait = ""
        self._params: dict[str, object] = {}
        self._setpoint = LiveControls()
        self._mode: Mode = "driving"
        self._source: Source | None = None
        self._model: TrackModel | None = None
        self._last: FloatArray | None = None
        self._time_s: float | None = None
        self._speed_limit = 0.0
        self._models: dict[tuple[str, tuple[tuple[str, object], ...]], TrackModel] = {}
        self.governed_cycles = 0

    # -- what the driver does --------------------------------------------------------------
    def start(self, pose_rad: npt.ArrayLike) -> None:
        """Begin holding ``pose_rad`` (N,) (the measured pose, clipped into the limits)."""
        pose = np.clip(self._vector("pose_rad", pose_rad), self.lower, self.upper)
        self._source = Hold(pose, "start")
        self._last = None
        self._time_s = None

    def check(self, name: str, params: Mapping[str, object] | None = None) -> None:
        """Raise GaitError unless gait ``name`` with ``params`` can be driven live here."""
        self._track_model(name, params)

    def select(self, name: str, params: Mapping[str, object] | None = None) -> None:
        """Blend into gait ``name`` (with ``params`` over its defaults) at the current set
        point; also resumes a pause. Raises GaitError for an unknown gait, bad parameters or a
        gait that cannot be driven live; the current motion then goes on unchanged."""
        if self._mode == "stopping":
            return
        model = self._track_model(name, params)
        self._gait, self._params, self._model = name, dict(params or {}), model
        self._setpoint = self._clip(self._setpoint)
        self._mode = "driving"
        if self._source is not None:  # else the first command starts it from the measured pose
            self._fade_to(Track.start(model, self._setpoint, self._source.pose()))

    def set_controls(self, controls: LiveControls) -> LiveControls:
        """Set the controls to approach (clipped into the gait's bounds and the speed the
        servos allow at that amplitude); returns what was set."""
        self._setpoint = self._clip(controls)
        return self._setpoint

    @property
    def setpoint(self) -> LiveControls:
        """The controls being approached."""
        return self._setpoint

    def pause(self) -> None:
        """Blend to the rest pose; ``resume`` (or ``select``) plays the gait again."""
        if self._mode == "driving":
            self._fade_to(Hold(self.rest, "rest"))
            self._mode = "paused"

    def resume(self) -> None:
        """Blend back into the gait driven before the pause."""
        if self._mode == "paused" and self._gait:
            self.select(self._gait, self._params)

    def stop(self) -> None:
        """Blend to the rest pose for good; ``finished`` turns true once it is reached."""
        if self._mode != "stopping":
            self._fade_to(Hold(self.rest, "rest"))
            self._mode = "stopping"

    @property
    def finished(self) -> bool:
        """True once a stop has brought the targets exactly to the rest pose."""
        return (
            self._mode == "stopping"
            and isinstance(self._source, Hold)
            and self._last is not None
            and bool(np.array_equal(self._last, self.rest))
        )

    def status(self) -> LiveStatus:
        """What is being driven now."""
        track = None if self._source is None else newest_track(self._source)
        blend = None if self._source is None else newest_blend(self._source)
        return LiveStatus(
            gait=self._gait,
            mode=self._mode,
            setpoint=self._setpoint,
            controls=None if track is None else track.controls,
            bounds=None if self._model is None else self._model.bounds,
            speed_limit=self._speed_limit,
            blend=None if blend is None else blend.fraction,
            blend_left_s=0.0 if blend is None else max(blend.duration_s - blend.elapsed_s, 0.0),
            phase_rad=() if track is None else tuple(float(v) for v in track.phases),
            governed_cycles=self.governed_cycles,
            finished=self.finished,
        )

    # -- the Gait interface ----------------------------------------------------------------
    def command(self, time_s: float, measured_rad: FloatArray | None = None) -> FloatArray:
        """Targets (N,) in rad at robot time ``time_s`` s: the state advanced by the time since
        the last call (none on the first, which starts from ``measured_rad`` if ``start`` was
        not called), governed so the step from the last targets stays within the budget."""
        if self._source is None:
            self.start(self.rest if measured_rad is None else measured_rad)
            if self._gait:
                self.select(self._gait, self._params)
        assert self._source is not None
        dt = 0.0 if self._time_s is None else max(float(time_s) - self._time_s, 0.0)
        self._time_s = float(time_s)
        source, pose = self._advance(self._source, dt)
        self._source, self._last = source, pose
        return pose.copy()

    def targets(self, time_s: float | npt.ArrayLike) -> FloatArray:
        """Not available: a live gait depends on what the driver did, not on time alone."""
        raise GaitError("a live gait is played cycle by cycle with command(); it has no targets(t)")

    @property
    def uses_measured_pose(self) -> bool:
        """True: its commands cannot be computed ahead of the run."""
        return True

    def reset(self) -> None:
        """Forget the motion: the next command starts again from the measured pose."""
        self._source, self._last, self._time_s = None, None, None
        self._mode = "driving"

    # -- inside ----------------------------------------------------------------------------
    def _track_model(self, name: str, params: Mapping[str, object] | None) -> TrackModel:
        """The gait's model, built once per (name, params): a key press reuses it."""
        resolved = resolve_params(name, params)
        key = (name, tuple(sorted(resolved.items())))
        model = self._models.get(key)
        if model is None:
            model = TrackModel(
                get_spec(name),
                resolved,
                self.joint_count,
                self.lower,
                self.upper,
                self.steer,
                self.smoothing_s,
            )
            self._models[key] = model
        return model

    def _advance(self, source: Source, dt_s: float) -> tuple[Source, FloatArray]:
        budget = self.speed_budget_rad_s * self.control_period_s
        fraction = 1.0
        for _ in range(_GOVERNOR_TRIES):
            candidate = source.advanced(fraction * dt_s, self._setpoint)
            pose = np.clip(candidate.pose(), self.lower, self.upper)
            step = 0.0 if self._last is None else float(np.max(np.abs(pose - self._last)))
            if step <= budget:
                if fraction < 1.0:
                    self.governed_cycles += 1
                return candidate, pose
            fraction *= min(0.5, 0.95 * budget / step)
        self.governed_cycles += 1
        assert self._last is not None
        return source, self._last  # not one step fits: hold this cycle, try again next

    def _fade_to(self, incoming: Source) -> None:
        if self._source is None:
            self._source = Hold(self.rest, "start")
        self._source = blend_into(
            self._source,
            incoming,
            duration_s=self.transition_s,
            speed_budget_rad_s=self.speed_budget_rad_s,
            setpoint=self._setpoint,
        )

    def _clip(self, controls: LiveControls) -> LiveControls:
        if self._model is None:
            return controls
        clipped = self._model.bounds.clip(controls)
        peak = self._model.peak_speed_rad_s(replace(clipped, speed=1.0))
        fastest = self._model.bounds.speed[1]
        if peak > 0.0:
            fastest = min(fastest, self.speed_budget_rad_s / peak)
        self._speed_limit = fastest
        return replace(clipped, speed=min(max(clipped.speed, -fastest), fastest))

    def _vector(self, key: str, value: npt.ArrayLike) -> FloatArray:
        try:
            out = np.broadcast_to(np.asarray(value, dtype=np.float64), (self.joint_count,))
        except ValueError as exc:
            raise GaitError(
                f"live gait: {key} must be one number or {self.joint_count} numbers ({exc})"
            ) from exc
        if not np.all(np.isfinite(out)):
            raise GaitError(f"live gait: {key} must be finite")
        return out.copy()
