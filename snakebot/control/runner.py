"""The fixed-rate control loop: gait -> safety -> backend, telemetry every cycle.

The runner never knows which backend it drives: the backend lets ``dt`` pass (the twin steps
physics, hardware sleeps to the deadline). Ctrl-C or SIGTERM (as KeyboardInterrupt) during the
gait starts the ramp-out; the scored window ends there.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from snakebot.backends.base import Backend, JointCommand
from snakebot.control.metrics import RunMetrics
from snakebot.control.safety import SafetyLayer, smooth_ramp
from snakebot.gaits import Gait
from snakebot.telemetry import CsvTelemetryWriter

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

    ``on_cycle(cycle, gait_time_s)`` runs after every cycle (progress, video, viewer).
    """
    dt = 1.0 / plan.rate_hz
    state = backend.read_state()
    safety.reset(state.position_rad)
    gait.reset()
    metrics.start(state.time_s, backend.body_state())
    start_s = state.time_s
    cycle = 0
    interrupted = False

    def step(gait_time_s: float, amplitude: float, scored: bool) -> None:
        nonlocal state, cycle
        target = gait.command(gait_time_s, state.position_rad)
        command = safety.filter(target, dt, amplitude)
        backend.send_command(JointCommand(command))
        backend.advance(dt)
        state = backend.read_state()
        body = backend.body_state()
        if scored:
            metrics.add(command, state, body, dt)
        if log is not None:
            com = None if body is None else body.com_m
            log.write(
                state.time_s,
                cycle,
                command,
                state.position_rad,
                state.velocity_rad_s,
                state.effort_nm,
                com,
            )
        cycle += 1
        if on_cycle is not None:
            on_cycle(cycle, gait_time_s)

    # Gait time is robot time, so a bus slower than the requested rate plays the gait at its true
    # speed with fewer updates, never in slow motion. Half a period of slack absorbs float sums.
    slack = 0.5 * dt
    try:
        while (gait_time := state.time_s - start_s) < plan.duration_s - slack:
            step(gait_time, safety.ramp_in(gait_time), scored=True)
    except KeyboardInterrupt:
        interrupted = True
    gait_end_s = state.time_s - start_s
    if plan.ramp_out and safety.ramp_s > 0:
        start_amplitude = safety.ramp_in(gait_end_s)
        fraction = 1.0
        while fraction > 0.0:  # the last command is exactly the rest pose, whatever the timing
            elapsed = state.time_s - start_s - gait_end_s
            fraction = max(0.0, 1.0 - (elapsed + dt) / safety.ramp_s)
            if fraction < slack / safety.ramp_s:
                fraction = 0.0
            step(gait_end_s + elapsed, start_amplitude * smooth_ramp(fraction), scored=False)
    summary = metrics.summary(gait.period_s)
    summary["rate_hz"] = plan.rate_hz
    summary["achieved_rate_hz"] = _achieved_rate(metrics, dt)
    summary["overruns"] = backend.stats.overruns
    summary["interrupted"] = interrupted
    return RunResult(summary, interrupted, 0 if log is None else log.rows)


def _achieved_rate(metrics: RunMetrics, dt: float) -> float:
    start = metrics.start_time_s or 0.0
    elapsed = metrics.end_time_s - start
    return metrics.cycles / elapsed if elapsed > 0 else 1.0 / dt
