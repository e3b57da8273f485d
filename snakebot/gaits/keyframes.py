"""Keyframe gaits after the GA pose-tracking report: interpolation, mirroring, error advance."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline

from snakebot.errors import GaitError
from snakebot.gaits.base import (
    FloatArray,
    Gait,
    PhasedGait,
    as_times,
    check_finite,
    check_joint_count,
    shaped,
)
from snakebot.gaits.spec import FLAG_UNIT, GaitSpec, ParamSpec, ParamValues

INTERPOLATIONS = ("linear", "cubic")
ADVANCES = ("time", "error")


def default_poses(joint_count: int) -> tuple[float, ...]:
    """Four S-curve poses (4*N,) in rad: a 0.4 rad, 0.7 rad/joint wave a quarter cycle apart."""
    joints = np.arange(joint_count)
    phases = np.arange(4)[:, None] * (math.pi / 2)
    return tuple(float(v) for v in (0.4 * np.sin(phases - 0.7 * joints)).ravel())


@dataclass
class _AdvanceState:
    segment: int = 0
    start_s: float | None = None


@dataclass(frozen=True)
class KeyframeGait(PhasedGait):
    """A cycle through P poses (flat P*N tuple, rad); segment k lasts durations[k] s.

    mirror appends the negated poses (a left/right mirror), doubling the cycle. targets() is
    the time schedule; with advance="error", command() holds each keyframe until the measured
    pose is within error_threshold_rad of it (or timeout_s has passed), then moves on.
    One phase for the time schedule, 2*pi*t/period_s: a full turn is one cycle.
    """

    joint_count: int
    poses: tuple[float, ...] = ()
    durations: tuple[float, ...] = (0.5,)
    interpolation: str = "cubic"
    mirror: bool = False
    advance: str = "time"
    error_threshold_rad: float = 0.05
    timeout_s: float = 2.0
    _cycle: FloatArray = field(init=False, repr=False, compare=False)
    _knots: FloatArray = field(init=False, repr=False, compare=False)
    _spline: Any = field(init=False, repr=False, compare=False)
    _state: _AdvanceState = field(
        default_factory=_AdvanceState, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        n = check_joint_count("keyframes", self.joint_count)
        flat = np.asarray(self.poses or default_poses(n), dtype=np.float64)
        if flat.ndim != 1 or flat.size == 0 or flat.size % n:
            raise GaitError(
                f"keyframes.poses: expected a multiple of N={n} values in rad "
                f"(P poses of {n} joints, head to tail), got {flat.size}"
            )
        if not np.all(np.isfinite(flat)):
            raise GaitError("keyframes.poses: expected finite numbers in rad")
        keys = flat.reshape(-1, n)
        durations = np.asarray(self.durations, dtype=np.float64)
        if durations.size not in (1, len(keys)) or not np.all(durations > 0.0):
            raise GaitError(
                f"keyframes.durations: expected 1 or {len(keys)} positive values in s "
                f"(one per keyframe), got {self.durations!r}"
            )
        for key, value, choices in (
            ("interpolation", self.interpolation, INTERPOLATIONS),
            ("advance", self.advance, ADVANCES),
        ):
            if value not in choices:
                raise GaitError(
                    f"keyframes.{key}: expected one of {', '.join(choices)}, got {value!r}"
                )
        check_finite(
            "keyframes", error_threshold_rad=self.error_threshold_rad, timeout_s=self.timeout_s
        )
        if self.error_threshold_rad <= 0.0 or self.timeout_s < 0.0:
            raise GaitError(
                "keyframes: expected error_threshold_rad > 0 rad and timeout_s >= 0 s, got "
                f"{self.error_threshold_rad:g} and {self.timeout_s:g}"
            )
        durations = np.broadcast_to(durations, len(keys))
        if self.mirror:
            keys, durations = np.vstack([keys, -keys]), np.concatenate([durations, durations])
        cycle = np.vstack([keys, keys[:1]])
        knots = np.concatenate([[0.0], np.cumsum(durations)])
        spline = None
        if self.interpolation == "cubic":
            spline = CubicSpline(knots, cycle, bc_type="periodic", axis=0)
        object.__setattr__(self, "_cycle", cycle)
        object.__setattr__(self, "_knots", knots)
        object.__setattr__(self, "_spline", spline)

    @property
    def period_s(self) -> float:
        """Nominal cycle length in s: the sum of the durations (doubled by mirror)."""
        return float(self._knots[-1])

    @property
    def gait_label(self) -> str:
        """ "keyframes"."""
        return "keyframes"

    @property
    def phase_rates_rad_s(self) -> FloatArray:
        """[2*pi/period_s] in rad/s."""
        return np.array([2.0 * math.pi / self.period_s])

    @property
    def uses_measured_pose(self) -> bool:
        """True with advance="error": command() waits for the measured pose to reach a keyframe."""
        return self.advance == "error"

    @property
    def keyframe_poses(self) -> FloatArray:
        """The cycle's keyframes (Q, N) in rad, mirrored ones included."""
        return self._cycle[:-1].copy()

    @property
    def keyframe_times_s(self) -> FloatArray:
        """When the schedule passes through each keyframe (Q,), in s from the cycle start."""
        return self._knots[:-1].copy()

    def _at_phases(self, phases: FloatArray) -> FloatArray:
        turns = phases[:, 0] / (2.0 * math.pi)
        return self._schedule(np.mod(turns, 1.0) * self.period_s)

    def command(self, time_s: float, measured_rad: FloatArray | None = None) -> FloatArray:
        """Targets (N,) in rad; with advance="error" each keyframe is held until reached."""
        if self.advance == "time":
            return self.targets(time_s)
        t = float(as_times("keyframes", time_s)[0][0])
        state = self._state
        if state.start_s is None or t < state.start_s:
            state.segment, state.start_s = 0, t
        elapsed = t - state.start_s
        duration = self._knots[state.segment + 1] - self._knots[state.segment]
        if elapsed < duration:
            return shaped(self._schedule(np.array([self._knots[state.segment] + elapsed])), True)
        goal: FloatArray = self._cycle[state.segment + 1].copy()
        if (
            measured_rad is None
            or self._reached(goal, measured_rad)
            or (elapsed >= duration + self.timeout_s)
        ):
            state.segment = (state.segment + 1) % (len(self._cycle) - 1)
            state.start_s = t
        return goal

    def reset(self) -> None:
        """Restart error-based advance at keyframe 0 on the next command."""
        self._state.segment, self._state.start_s = 0, None

    def _reached(self, goal: FloatArray, measured_rad: FloatArray) -> bool:
        measured = np.asarray(measured_rad, dtype=np.float64)
        if measured.shape != goal.shape:
            raise GaitError(
                f"keyframes: measured_rad must have shape ({self.joint_count},), "
                f"got {measured.shape}"
            )
        return bool(np.max(np.abs(measured - goal)) < self.error_threshold_rad)

    def _schedule(self, cycle_time: FloatArray) -> FloatArray:
        if self._spline is not None:
            return np.asarray(self._spline(cycle_time), dtype=np.float64)
        last = len(self._knots) - 2
        k = np.clip(np.searchsorted(self._knots, cycle_time, side="right") - 1, 0, last)
        frac = (cycle_time - self._knots[k]) / (self._knots[k + 1] - self._knots[k])
        return self._cycle[k] + frac[:, None] * (self._cycle[k + 1] - self._cycle[k])


def _build(joint_count: int, p: ParamValues, _lower: FloatArray, _upper: FloatArray) -> Gait:
    return KeyframeGait(
        joint_count,
        poses=p.numbers("poses"),
        durations=p.numbers("durations"),
        interpolation=p.text("interpolation"),
        mirror=p.flag("mirror"),
        advance=p.text("advance"),
        error_threshold_rad=p.number("error_threshold_rad"),
        timeout_s=p.number("timeout_s"),
    )


def _tuning_start(joint_count: int, fixed: Mapping[str, object]) -> dict[str, object]:
    """Unless poses are fixed, start from half a mirrored cycle: the GA report's genome.

    The first two of the default four S-curve poses, mirrored, give the same four keyframes and
    half the genes.
    """
    params = dict(fixed)
    if "poses" not in params:
        params["poses"] = default_poses(joint_count)[: 2 * joint_count]
        params.setdefault("mirror", 1.0)
    return params


SPEC = GaitSpec(
    name="keyframes",
    summary=(
        "Cycle through keyframe poses with linear or periodic-cubic interpolation, optional "
        "mirroring and error-based advance (GA pose-tracking report)."
    ),
    params=(
        # +-pi/4: the GA report's 90 degree range, clipped to the joint limits when tuning.
        ParamSpec(
            "poses",
            "rad",
            (),
            "P poses of N angles, flattened; empty = 4-pose S-curve",
            bounds=(-math.pi / 4, math.pi / 4),
            tunable=True,
            joint_poses=True,
        ),
        ParamSpec(
            "durations",
            "s",
            (0.5,),
            "time from each keyframe to the next; 1 or P values",
            bounds=(0.2, 1.5),
        ),
        ParamSpec("interpolation", "", "cubic", "between keyframes", INTERPOLATIONS),
        ParamSpec("mirror", FLAG_UNIT, 0.0, "1: continue the cycle with the poses negated"),
        ParamSpec(
            "advance", "", "time", "time: fixed schedule; error: wait for the pose", ADVANCES
        ),
        ParamSpec("error_threshold_rad", "rad", 0.05, "max |measured - keyframe| to advance"),
        ParamSpec("timeout_s", "s", 2.0, "longest wait at a keyframe before advancing anyway"),
    ),
    factory=_build,
    tuning_start=_tuning_start,
)
