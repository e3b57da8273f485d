"""The fixed-rate control loop: gait -> safety -> backend, telemetry every cycle.

The runner never knows which backend it drives: the backend lets ``dt`` pass (the twin steps
physics, hardware sleeps to the deadline). The cycle itself (schedule, commands, what each cycle
records) is the one every loop shares: snakebot.control.cycle and snakebot.control.loop. How a
run ends:

- The gait window closes (``plan.duration_s``), or a ``stop()`` check gives a reason: ramp-out,
  and the run is not counted as interrupted.
- Ctrl-C or SIGTERM (as KeyboardInterrupt) during the gait starts the ramp-out; the scored window
  ends there. The stop signals are held back to the start of the next cycle
  (snakebot.interrupts), so the cycle they came in is whole in every observer. Another one
  during the ramp-out ends it at once and propagates: the backend's ``close`` then stops at the
  joint speed limit, still ending in the stop policy.
- Any other error while the bus still works (the gait raised, the safety layer refused its
  output, telemetry or a per-cycle hook failed) ramps out too, holding the gait's last good target
  while the amplitude falls, then re-raises the error. What failed is left out of the ramp-out.
- A BackendError (the bus, a servo, the twin) is re-raised at once: the backend's ``close`` does
  what it can.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from snakebot.backends.base import Backend
from snakebot.control.cycle import (
    CycleHook,
    CycleObserver,
    CycleRecord,
    CycleSchedule,
    CycleSink,
    GaitCycle,
    StopCheck,
)
from snakebot.control.loop import CycleLoop
from snakebot.control.metrics import RunMetrics
from snakebot.control.safety import SafetyLayer, smooth_ramp
from snakebot.control.summary import run_summary
from snakebot.errors import BackendError
from snakebot.gaits import Gait
from snakebot.gaits.table import CommandTable
from snakebot.interrupts import DeferredInterrupts

__all__ = [
    "CycleHook",
    "CycleObserver",
    "CycleRecord",
    "RunPlan",
    "RunResult",
    "play_commands",
    "run_gait",
]


@dataclass(frozen=True)
class RunPlan:
    """How long and how fast to run: gait duration (None: until ``stop`` or Ctrl-C says so),
    control rate and the ramp-out after it. Raises ValueError for a duration or rate that is not
    a positive finite number."""

    duration_s: float | None
    rate_hz: float = 100.0
    ramp_out: bool = True

    def __post_init__(self) -> None:
        self.schedule(0.0)  # validates

    def schedule(self, ramp_s: float, timestep_s: float | None = None) -> CycleSchedule:
        """The cycle schedule of this plan with a ``ramp_s`` amplitude ramp."""
        return CycleSchedule(self.rate_hz, self.duration_s, ramp_s, self.ramp_out, timestep_s)


@dataclass
class RunResult:
    """What a run produced: the summary dict, whether it was interrupted, and the reason a
    ``stop`` check gave ("" when none did)."""

    summary: dict[str, object]
    interrupted: bool = False
    log_rows: int = 0
    extra: dict[str, object] = field(default_factory=dict)
    stopped_by: str = ""


def run_gait(
    backend: Backend,
    gait: Gait,
    safety: SafetyLayer,
    plan: RunPlan,
    metrics: RunMetrics,
    *,
    log: CycleSink | None = None,
    on_cycle: CycleHook | None = None,
    observers: Sequence[CycleObserver] = (),
    stop: StopCheck | None = None,
) -> RunResult:
    """Run ``gait`` on a connected ``backend`` for ``plan.duration_s``, then ramp out.

    ``log`` (a telemetry sink: snakebot.telemetry.sink) and then each of ``observers`` get every
    cycle's ``CycleRecord``, then ``on_cycle(cycle, gait_time_s)`` runs (progress, video,
    viewer); ``RunResult.log_rows`` are the rows ``log`` took. ``stop()`` is asked before every gait
    cycle: a reason ends the gait there as Ctrl-C does (ramp-out, then ``RunResult.stopped_by``);
    with ``plan.duration_s`` None only ``stop`` or Ctrl-C ends the gait. Raises what ended the
    run early (after the ramp-out where the bus still works; see the module doc), and, before
    the first cycle, the backend's ConfigError for a rate it cannot hold (``check_rate``).
    """
    backend.check_rate(plan.rate_hz)  # a servo bus that cannot hold the rate refuses it here
    schedule = plan.schedule(safety.ramp_s)
    loop = CycleLoop(
        backend,
        GaitCycle([gait], safety),
        schedule,
        metrics,
        on_cycle=on_cycle,
        observers=[*([] if log is None else [log]), *observers],
    )
    loop.start()
    interrupted = False
    stopped_by = ""
    failure: Exception | None = None
    signals = DeferredInterrupts()  # a stop signal reaches the loop between cycles
    signals.arm()
    try:
        try:
            while schedule.in_gait(loop.elapsed_s):
                signals.deliver()
                if stop is not None and (reason := stop()) is not None:
                    stopped_by = reason
                    break
                loop.gait_step()
        except KeyboardInterrupt:
            interrupted = True
        except BackendError:
            raise
        except Exception as exc:
            if loop.stage == "backend":
                raise
            failure = exc
            loop.leave_out(loop.stage)
        if plan.ramp_out and safety.ramp_s > 0:
            _ramp_out(loop, safety, loop.elapsed_s, failure, signals)
    except BaseException:
        signals.abandon()
        raise
    if failure is not None:
        signals.abandon()
        raise failure
    signals.release()  # one that came in the last cycle: raised now
    summary = run_summary(
        metrics,
        backend,
        rate_hz=plan.rate_hz,
        gait_period_s=gait.period_s,
        interrupted=interrupted,
    )
    return RunResult(summary, interrupted, 0 if log is None else log.rows, stopped_by=stopped_by)


def play_commands(
    backend: Backend,
    commands: np.ndarray,
    rate_hz: float,
    safety: SafetyLayer,
    *,
    observers: Sequence[CycleObserver] = (),
) -> list[CycleRecord]:
    """Play a command table (T, N) rad on a connected ``backend``, one row per control period,
    through the control loop; returns every cycle's record (each of ``observers`` sees them).

    The table is a gait (snakebot.gaits.table.CommandTable) behind ``safety``, usually
    ``SafetyLayer.clip_only(robot)``: step tests and chirps must reach the servo as they were
    made. There is no ramp-out, the table's last row is where it ends. On the twin that is T
    cycles; a late cycle (a slow bus) plays the row of its time, so there may be fewer.
    Raises the backend's ConfigError for a rate it cannot hold before the first command,
    GaitError for a table that is not (T, N) finite angles, and what the loop raises.
    """
    backend.check_rate(rate_hz)
    schedule = CycleSchedule(rate_hz)
    table = CommandTable(commands, schedule.period_s)
    schedule = CycleSchedule(rate_hz, table.duration_s)
    records: list[CycleRecord] = []
    loop = CycleLoop(
        backend,
        GaitCycle([table], safety),
        schedule,
        None,
        observers=[records.append, *observers],
    )
    loop.start()
    while schedule.in_gait(gait_time := loop.elapsed_s):
        loop.step(gait_time, 1.0, scored=True)
    return records


def _ramp_out(
    loop: CycleLoop,
    safety: SafetyLayer,
    gait_end_s: float,
    failure: Exception | None,
    signals: DeferredInterrupts,
) -> None:
    """Ramp the amplitude to zero over ``safety.ramp_s``; the last command is the rest pose.

    Late cycles (a loaded host) shorten the ramp in cycles, not in time; the slew limit may then
    hold the command back, so the ramp goes on at zero amplitude until it reaches the rest pose.

    A KeyboardInterrupt here (``signals`` deliver at the start of each cycle) ends the ramp: it
    propagates when nothing else failed (the backend then stops fast), and gives way to
    ``failure`` otherwise. With ``failure`` pending, anything
    else that goes wrong also ends the ramp; ``failure`` is what the caller raises.
    """
    schedule = loop.schedule
    start_amplitude = schedule.ramp_in(gait_end_s)
    fraction = 1.0
    try:
        while fraction > 0.0:
            since_end = loop.elapsed_s - gait_end_s
            fraction = schedule.ramp_out_fraction(since_end)
            signals.deliver()
            loop.step(gait_end_s + since_end, start_amplitude * smooth_ramp(fraction), scored=False)
        # The last command is exactly the rest pose, whatever the timing.
        span = float(np.max(np.abs(loop.command - safety.rest_rad)))
        for _ in range(math.ceil(span / (safety.max_speed_rad_s * schedule.period_s)) + 1):
            if np.array_equal(loop.command, safety.rest_rad):
                break
            since_end = loop.elapsed_s - gait_end_s
            signals.deliver()
            loop.step(gait_end_s + since_end, 0.0, scored=False)
    except KeyboardInterrupt:
        if failure is None:
            raise
    except Exception as exc:
        if failure is None:
            raise
        failure.add_note(f"the ramp-out after it stopped too: {exc!r}")
