"""The fixed-rate control loop: gait -> safety -> backend, telemetry every cycle.

The runner never knows which backend it drives: the backend lets ``dt`` pass (the twin steps
physics, hardware sleeps to the deadline). How a run ends:

- Ctrl-C or SIGTERM (as KeyboardInterrupt) during the gait starts the ramp-out; the scored window
  ends there. Another one during the ramp-out ends it at once and propagates: the backend's
  ``close`` then stops at the joint speed limit, still ending in the stop policy.
- Any other error while the bus still works (the gait raised, the safety layer refused its
  output, telemetry or a per-cycle hook failed) ramps out too, holding the gait's last good target
  while the amplitude falls, then re-raises the error. What failed is left out of the ramp-out.
- A BackendError (the bus, a servo, the twin) is re-raised at once: the backend's ``close`` does
  what it can.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from snakebot.backends.base import Backend
from snakebot.control.metrics import RunMetrics
from snakebot.control.safety import SafetyLayer, smooth_ramp
from snakebot.errors import BackendError
from snakebot.gaits import Gait
from snakebot.telemetry import CsvTelemetryWriter
from snakebot.types import JointCommand, JointState

CycleHook = Callable[[int, float], None]


@dataclass(frozen=True)
class RunPlan:
    """How long and how fast to run: gait duration, control rate and the ramp-out after it."""

    duration_s: float
    rate_hz: float = 100.0
    ramp_out: bool = True

    def __post_init__(self) -> None:
        if not (self.duration_s > 0 and math.isfinite(self.duration_s)):
            raise ValueError(
                f"duration must be a positive number of seconds, got {self.duration_s}"
            )
        if not (self.rate_hz > 0 and math.isfinite(self.rate_hz)):
            raise ValueError(f"rate must be a positive number of Hz, got {self.rate_hz}")


@dataclass
class RunResult:
    """What a run produced: the summary dict and whether it was interrupted."""

    summary: dict[str, object]
    interrupted: bool = False
    log_rows: int = 0
    extra: dict[str, object] = field(default_factory=dict)


class _Loop:
    """One run's cycle: which parts still take part (a failed one is left out of the ramp-out)."""

    def __init__(
        self, backend: Backend, gait: Gait, safety: SafetyLayer, metrics: RunMetrics, dt: float,
        log: CsvTelemetryWriter | None, on_cycle: CycleHook | None,
    ) -> None:
        self.backend, self.gait, self.safety, self.metrics = backend, gait, safety, metrics
        self.dt, self.log, self.on_cycle = dt, log, on_cycle
        self.state: JointState = backend.read_state()
        self.target: np.ndarray = self.state.position_rad.copy()  # the gait's last good target
        self.command: np.ndarray = self.state.position_rad.copy()  # the last command sent
        self.use_gait = True
        self.cycle = 0
        self.stage = "gait"

    def step(self, gait_time_s: float, amplitude: float, scored: bool) -> None:
        """One cycle; ``stage`` names the part running when an exception leaves."""
        backend = self.backend
        self.stage = "gait"
        if self.use_gait:
            target = self.gait.command(gait_time_s, self.state.position_rad)
        else:
            target = self.target
        self.stage = "safety"
        command = self.safety.filter(target, self.dt, amplitude)
        self.target, self.command = target, command
        self.stage = "backend"
        backend.send_command(JointCommand(command))
        backend.advance(self.dt)
        self.state = state = backend.read_state()
        body = backend.body_state()
        self.stage = "metrics"
        if scored:
            self.metrics.add(command, state, body, self.dt)
        self.stage = "log"
        if self.log is not None:
            com = None if body is None else body.com_m
            imu = None if body is None else (body.head_quat, body.head_gyro_rad_s)
            self.log.write(state.time_s, self.cycle, command, state.position_rad,
                           state.velocity_rad_s, state.effort_nm, com, imu)
        self.cycle += 1
        self.stage = "hook"
        if self.on_cycle is not None:
            self.on_cycle(self.cycle, gait_time_s)

    def leave_out(self, stage: str) -> None:
        """Drop the part that failed from the ramp-out that follows."""
        if stage in ("gait", "safety"):
            self.use_gait = False  # hold the last target the safety layer accepted
        elif stage == "log":
            self.log = None
        elif stage == "hook":
            self.on_cycle = None


def run_gait(
    backend: Backend,
    gait: Gait,
    safety: SafetyLayer,
    plan: RunPlan,
    metrics: RunMetrics,
    *,
    log: CsvTelemetryWriter | None = None,
    on_cycle: CycleHook | None = None,
) -> RunResult:
    """Run ``gait`` on a connected ``backend`` for ``plan.duration_s``, then ramp out.

    ``on_cycle(cycle, gait_time_s)`` runs after every cycle (progress, video, viewer). Raises
    what ended the run early (after the ramp-out where the bus still works; see the module doc).
    """
    dt = 1.0 / plan.rate_hz
    loop = _Loop(backend, gait, safety, metrics, dt, log, on_cycle)
    safety.reset(loop.state.position_rad)
    gait.reset()
    metrics.start(loop.state.time_s, backend.body_state())
    start_s = loop.state.time_s
    interrupted = False
    failure: Exception | None = None

    # Gait time is robot time, so a bus slower than the requested rate plays the gait at its true
    # speed with fewer updates, never in slow motion. Half a period of slack absorbs float sums.
    slack = 0.5 * dt
    try:
        while (gait_time := loop.state.time_s - start_s) < plan.duration_s - slack:
            loop.step(gait_time, safety.ramp_in(gait_time), scored=True)
    except KeyboardInterrupt:
        interrupted = True
    except BackendError:
        raise
    except Exception as exc:
        if loop.stage == "backend":
            raise
        failure = exc
        loop.leave_out(loop.stage)
    gait_end_s = loop.state.time_s - start_s
    if plan.ramp_out and safety.ramp_s > 0:
        _ramp_out(loop, safety, start_s, gait_end_s, slack, failure)
    if failure is not None:
        raise failure
    summary = metrics.summary(gait.period_s)
    summary["rate_hz"] = plan.rate_hz
    summary["achieved_rate_hz"] = _achieved_rate(metrics, dt)
    summary["overruns"] = backend.stats.overruns
    summary["backend_stats"] = dict(backend.stats.extra)
    summary["interrupted"] = interrupted
    health = getattr(backend, "physics_health", None)  # the twin's physics checks
    if callable(health) and (physics := health()) is not None:
        summary["physics"] = physics
    return RunResult(summary, interrupted, 0 if log is None else log.rows)


def _ramp_out(
    loop: _Loop, safety: SafetyLayer, start_s: float, gait_end_s: float, slack: float,
    failure: Exception | None,
) -> None:
    """Ramp the amplitude to zero over ``safety.ramp_s``; the last command is the rest pose.

    Late cycles (a loaded host) shorten the ramp in cycles, not in time; the slew limit may then
    hold the command back, so the ramp goes on at zero amplitude until it reaches the rest pose.

    A KeyboardInterrupt here ends the ramp: it propagates when nothing else failed (the backend
    then stops fast), and gives way to ``failure`` otherwise. With ``failure`` pending, anything
    else that goes wrong also ends the ramp; ``failure`` is what the caller raises.
    """
    start_amplitude = safety.ramp_in(gait_end_s)
    fraction = 1.0
    try:
        while fraction > 0.0:
            elapsed = loop.state.time_s - start_s - gait_end_s
            fraction = max(0.0, 1.0 - (elapsed + loop.dt) / safety.ramp_s)
            if fraction < slack / safety.ramp_s:
                fraction = 0.0
            loop.step(gait_end_s + elapsed, start_amplitude * smooth_ramp(fraction), scored=False)
        # The last command is exactly the rest pose, whatever the timing.
        span = float(np.max(np.abs(loop.command - safety.rest_rad)))
        for _ in range(math.ceil(span / (safety.max_speed_rad_s * loop.dt)) + 1):
            if np.array_equal(loop.command, safety.rest_rad):
                break
            elapsed = loop.state.time_s - start_s - gait_end_s
            loop.step(gait_end_s + elapsed, 0.0, scored=False)
    except KeyboardInterrupt:
        if failure is None:
            raise
    except Exception as exc:
        if failure is None:
            raise
        failure.add_note(f"the ramp-out after it stopped too: {exc!r}")


def _achieved_rate(metrics: RunMetrics, dt: float) -> float:
    start = metrics.start_time_s or 0.0
    elapsed = metrics.end_time_s - start
    return metrics.cycles / elapsed if elapsed > 0 else 1.0 / dt
