"""Test signals for one joint (step, chirp) and what their responses say about the servo loop."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from snakebot.tuning.trace import FloatArray


@dataclass(frozen=True)
class StepMetrics:
    """A step response: 10-90 % rise time (s), overshoot past the goal or the final value
    (fraction of the step), time to stay within ``band`` of the step around the final value (s;
    NaN if still moving in the last fifth), and the final error (rad; the last fifth's mean).
    Friction can stop a joint short of its goal: that shows as steady-state error, not as an
    unsettled step."""

    rise_time_s: float
    overshoot: float
    settling_time_s: float
    steady_state_error_rad: float

    def as_dict(self) -> dict[str, float | None]:
        """JSON-ready; NaN becomes None."""
        values = {
            "rise_time_s": self.rise_time_s,
            "overshoot": self.overshoot,
            "settling_time_s": self.settling_time_s,
            "steady_state_error_rad": self.steady_state_error_rad,
        }
        return {k: None if math.isnan(v) else v for k, v in values.items()}


def step_commands(
    hold_rad: FloatArray,
    joint: int,
    step_rad: float,
    lower_rad: FloatArray,
    upper_rad: FloatArray,
    *,
    rate_hz: float,
    lead_s: float,
    step_s: float,
) -> FloatArray:
    """Commands (K, N): hold ``hold_rad`` for ``lead_s``, then move ``joint`` by ``step_rad``
    (towards the roomier side if the step would leave its limits) and hold for ``step_s``."""
    lead, after = round(lead_s * rate_hz), round(step_s * rate_hz)
    goal = hold_rad[joint] + step_rad
    if not lower_rad[joint] <= goal <= upper_rad[joint]:
        goal = hold_rad[joint] - step_rad
    commands = np.tile(hold_rad, (lead + after, 1))
    commands[lead:, joint] = goal
    return commands


def chirp_commands(
    hold_rad: FloatArray,
    joint: int,
    amplitude_rad: float,
    *,
    rate_hz: float,
    duration_s: float,
    start_hz: float = 0.2,
    stop_hz: float = 2.0,
) -> FloatArray:
    """Commands (K, N): ``joint`` follows a linear chirp from ``start_hz`` to ``stop_hz`` around
    its hold angle, the others hold; the amplitude fades in and out over the first and last 10 %."""
    t = np.arange(round(duration_s * rate_hz)) / rate_hz
    sweep = (stop_hz - start_hz) / duration_s
    phase = 2 * math.pi * (start_hz * t + 0.5 * sweep * t * t)
    fade = np.clip(np.minimum(t, duration_s - t) / (0.1 * duration_s), 0.0, 1.0)
    commands = np.tile(hold_rad, (len(t), 1))
    commands[:, joint] += amplitude_rad * fade * np.sin(phase)
    return commands


def step_metrics(
    time_s: FloatArray,
    position_rad: FloatArray,
    start_rad: float,
    goal_rad: float,
    step_time_s: float,
    band: float = 0.05,
) -> StepMetrics:
    """Metrics of a step from ``start_rad`` to ``goal_rad`` issued at ``step_time_s``."""
    after = time_s >= step_time_s - 1e-9
    t = time_s[after] - step_time_s
    y = (position_rad[after] - start_rad) / (goal_rad - start_rad)
    if y.size == 0:
        return StepMetrics(math.nan, math.nan, math.nan, math.nan)
    rise = _first(t, y >= 0.9) - _first(t, y >= 0.1)
    tail = max(1, y.size // 5)
    final = float(y[-tail:].mean())
    outside = np.flatnonzero(np.abs(y - final) > band)
    if outside.size == 0:
        settling = 0.0
    elif outside[-1] >= y.size - tail:
        settling = math.nan
    else:
        settling = float(t[outside[-1] + 1])
    return StepMetrics(
        rise_time_s=rise,
        overshoot=max(float(y.max()) - max(final, 1.0), 0.0),
        settling_time_s=settling,
        steady_state_error_rad=abs(final - 1.0) * abs(goal_rad - start_rad),
    )


def rms(error: FloatArray) -> float:
    """Root mean square of all entries."""
    return float(np.sqrt(np.mean(np.square(error)))) if error.size else math.nan


def _first(t: FloatArray, flags: np.ndarray) -> float:
    hits = np.flatnonzero(flags)
    return float(t[hits[0]]) if hits.size else math.nan
