"""One control cycle: its schedule, how its commands are made, and what each cycle records.

Every loop that drives joints uses these: ``run_gait`` (one run, any backend), the batched
tuning engine (B runs on ``mujoco.batch``), the tuning process pool and the soft-body tuning
(``run_gait`` in workers) and the live drive loop. A cycle is

    targets  = gait.command(gait_time, measured)             (GaitCycle.targets)
    commands = safety.filter(targets, slew period, amplitude) (GaitCycle.commands)
    send, let one period pass, read the state                 (the backend, or mujoco.batch)

and ``CycleSchedule`` says when: the gait time of each cycle, the amplitude ramp, which cycles are
scored and (for a simulated backend) the robot time of each cycle summed step by step as MuJoCo
sums it. Since the step-by-step runner and the batched engine ask the same schedule and make
commands with the same code, a tuned candidate replays in ``snakebot run`` bit for bit.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from snakebot.control.safety import SafetyLayer, smooth_ramp
from snakebot.gaits import Gait
from snakebot.types import BodyState, JointState

FloatArray = npt.NDArray[np.float64]

LATE_TOLERANCE = 1e-6
"""A cycle measured within this fraction of its period took the period (float sums, not late)."""

MAX_SLEW_PERIODS = 2.0
"""The slew limit follows a late cycle's measured length up to this many periods, so a stalled
bus never turns into a jump."""


@dataclass(frozen=True)
class CycleSchedule:
    """When each control cycle happens and what it does, for one run.

    ``rate_hz`` control cycles per second; ``duration_s`` of gait (the scored window), or None
    for an open-ended run that a stop condition ends; ``ramp_s`` the amplitude ramp at the start
    and, when ``ramp_out``, after the gait; ``timestep_s`` the physics step of a simulated
    backend (None where time is the wall clock). Raises ValueError for a rate or duration that
    is not a positive finite number, a negative ramp, or a period that is not a whole number of
    physics steps.
    """

    rate_hz: float = 100.0
    duration_s: float | None = None
    ramp_s: float = 0.0
    ramp_out: bool = True
    timestep_s: float | None = None

    def __post_init__(self) -> None:
        if not (self.rate_hz > 0 and math.isfinite(self.rate_hz)):
            raise ValueError(f"rate must be a positive number of Hz, got {self.rate_hz}")
        if self.duration_s is not None and not (
            self.duration_s > 0 and math.isfinite(self.duration_s)
        ):
            raise ValueError(
                f"duration must be a positive number of seconds, got {self.duration_s}"
            )
        if not (self.ramp_s >= 0 and math.isfinite(self.ramp_s)):
            raise ValueError(
                f"ramp must be zero or a positive number of seconds, got {self.ramp_s}"
            )
        if self.timestep_s is not None:
            steps = round(self.period_s / self.timestep_s)
            if steps < 1 or not math.isclose(steps * self.timestep_s, self.period_s, rel_tol=1e-6):
                raise ValueError(
                    f"control period {self.period_s:g} s is not a whole number of "
                    f"{self.timestep_s:g} s physics steps"
                )

    @functools.cached_property
    def period_s(self) -> float:
        """The control period, 1 / rate_hz."""
        return 1.0 / self.rate_hz

    @functools.cached_property
    def slack_s(self) -> float:
        """Half a period: absorbs float sums when deciding whether one more cycle fits."""
        return 0.5 * self.period_s

    @property
    def substeps(self) -> int:
        """Physics steps per control period (simulated backends; ValueError without a timestep)."""
        if self.timestep_s is None:
            raise ValueError("the schedule has no physics timestep (a wall-clock backend)")
        return round(self.period_s / self.timestep_s)

    def in_gait(self, gait_time_s: float) -> bool:
        """True when a cycle starting ``gait_time_s`` into the run is a scored gait cycle.

        Gait time is robot time, so a bus slower than the rate plays the gait at its true speed
        with fewer updates, never in slow motion.
        """
        return self.duration_s is None or gait_time_s < self.duration_s - self.slack_s

    def ramp_in(self, gait_time_s: float) -> float:
        """Amplitude factor 0..1 ``gait_time_s`` into the run (smoothstep over ``ramp_s``)."""
        return 1.0 if self.ramp_s <= 0 else smooth_ramp(gait_time_s / self.ramp_s)

    def ramp_out_fraction(self, since_gait_end_s: float) -> float:
        """How much of the ramp-out is left (1..0) at the next cycle's end, ``since_gait_end_s``
        after the gait stopped; 0 once less than half a period would be left."""
        fraction = max(0.0, 1.0 - (since_gait_end_s + self.period_s) / self.ramp_s)
        return 0.0 if fraction < self.slack_s / self.ramp_s else fraction

    def slew_period_s(self, cycle: int, last_period_s: float | None) -> float:
        """The time the slew limit allows for the command of cycle ``cycle`` (0 the first).

        ``last_period_s`` is how long the cycle before took in robot time, from one state read to
        the next. The first cycle's length also holds the time from connecting to the first
        command, so it counts from the third cycle on. A cycle within float noise of the period
        counts as the period; a late one (a loaded host, a slow bus) gives the joints the time
        that really passed, up to ``MAX_SLEW_PERIODS``.
        """
        period = self.period_s
        if cycle < 2 or last_period_s is None or last_period_s <= period * (1 + LATE_TOLERANCE):
            return period
        return min(last_period_s, MAX_SLEW_PERIODS * period)

    def cycle_times(self, max_cycles: float = math.inf) -> list[float]:
        """Robot time before each scored cycle and after the last, for a simulated backend.

        Summed physics step by physics step as MuJoCo sums ``data.time``, so the cycle count and
        gait times are exactly what ``run_gait`` measures on the twin. At most ``max_cycles``
        cycles; an open-ended schedule needs a finite ``max_cycles``.
        """
        if self.duration_s is None and math.isinf(max_cycles):
            raise ValueError("an open-ended schedule has no planned cycle times")
        timestep, steps = float(self.timestep_s or 0.0), self.substeps
        times = [0.0]
        while self.in_gait(times[-1]) and len(times) <= max_cycles:
            now = times[-1]
            for _ in range(steps):
                now += timestep
            times.append(now)
        return times

    @property
    def planned_cycles(self) -> int:
        """Scored cycles in a full run of a simulated backend (ValueError when open-ended)."""
        return len(self.cycle_times()) - 1


@dataclass(frozen=True)
class CycleRecord:
    """What one control cycle did, as observers see it (telemetry, display, tuning samples).

    ``cycle`` counts cycles done (1 for the first); ``gait_time_s`` is when the targets were
    made (robot seconds since the run started) and ``state`` was read after the command, at
    ``state.time_s``. ``target_rad`` is the gait's output, ``command_rad`` what the safety layer
    sent (both (N,) rad). ``period_s`` is the robot time the cycle took, ``overrun`` whether the
    backend missed its deadline in it, ``achieved_rate_hz`` cycles per second of robot time
    since the start. ``scored`` is False during the ramp-out. ``work_j`` (N,) J is each joint's
    positive work in the cycle, integrated over its physics steps by a backend that does
    (``JointState.positive_work_j``), else None.
    """

    cycle: int
    gait_time_s: float
    target_rad: FloatArray
    command_rad: FloatArray
    state: JointState
    body: BodyState | None
    amplitude: float
    scored: bool
    period_s: float
    overrun: bool
    achieved_rate_hz: float
    work_j: FloatArray | None = field(default=None, kw_only=True)

    @property
    def time_s(self) -> float:
        """Robot time the state was read."""
        return self.state.time_s

    @property
    def tracking_error_rad(self) -> FloatArray:
        """Command minus measured position per joint (N,) rad."""
        error: FloatArray = self.command_rad - self.state.position_rad
        return error


CycleObserver = Callable[[CycleRecord], None]
"""Sees every cycle's record: telemetry sinks, the drive display, tuning samples, a test.

The record is the only thing that leaves the loop, so a new channel is one field: of the
state or body a backend reads (the record carries them as they are: no edit to the loop), or of
the record where the loop itself makes it, plus the sinks that choose to show it. No sink's
signature changes and the sinks that do not show it never hear of it
(tests/integration/control/test_cycle_channel.py)."""


@runtime_checkable
class CycleSink(Protocol):
    """An observer that keeps what it sees (a CSV file, a Foxglove server, an MCAP file):
    ``rows`` counts the records taken, ``close`` flushes and releases (idempotent)."""

    @property
    def rows(self) -> int:
        """Records taken so far."""
        ...

    def __call__(self, record: CycleRecord) -> None:
        """Take one cycle's record."""
        ...

    def close(self) -> None:
        """Flush and release; idempotent."""
        ...


CycleHook = Callable[[int, float], None]
"""``hook(cycle, gait_time_s)`` after every cycle (progress, video, viewer)."""
StopCheck = Callable[[], str | None]
"""Asked before every gait cycle: a reason to stop (ends the gait as Ctrl-C does) or None."""


class GaitCycle:
    """B gaits through one safety layer over (B*N,): the one place a cycle's commands are made.

    The safety layer works elementwise, so one layer over the flattened batch gives each run the
    same clipping, slew limit and ramps as its own layer would; ``run_gait`` uses B = 1 with the
    caller's layer. Targets come from ``gait.command`` one run at a time: numpy's vectorised sin
    can differ from the one-element path in the last bit, and a replay must match to the bit.
    """

    def __init__(self, gaits: Sequence[Gait], safety: SafetyLayer) -> None:
        self.gaits = list(gaits)
        self.safety = safety

    @classmethod
    def tiled(cls, gaits: Sequence[Gait], safety: SafetyLayer) -> GaitCycle:
        """B gaits with a copy of ``safety`` (one run's layer) for each."""
        count = len(gaits)
        layer = SafetyLayer(
            np.tile(safety.lower_rad, count),
            np.tile(safety.upper_rad, count),
            safety.max_speed_rad_s,
            safety.ramp_s,
            np.tile(safety.rest_rad, count),
        )
        return cls(gaits, layer)

    @property
    def size(self) -> int:
        """B, the number of runs."""
        return len(self.gaits)

    @property
    def open_loop(self) -> bool:
        """True unless a gait uses the measured pose (keyframes with error advance, say)."""
        return not any(gait.uses_measured_pose for gait in self.gaits)

    def reset(self, measured_rad: FloatArray) -> None:
        """Reset every gait and start the safety layer from the measured poses ((B, N) or (N,))."""
        for gait in self.gaits:
            gait.reset()
        self.safety.reset(np.asarray(measured_rad, dtype=float).ravel())

    def targets(self, gait_time_s: float, measured_rad: FloatArray) -> FloatArray:
        """The gaits' targets at ``gait_time_s`` given the measured poses, rad: (N,) for one run
        measured as (N,), else (B, N) for poses (B, N)."""
        if measured_rad.ndim == 1:
            return self.gaits[0].command(gait_time_s, measured_rad)
        return np.stack(
            [
                gait.command(gait_time_s, measured)
                for gait, measured in zip(self.gaits, measured_rad, strict=True)
            ]
        )

    def commands(
        self, targets_rad: FloatArray, slew_period_s: float, amplitude: float
    ) -> FloatArray:
        """What the safety layer sends for ``targets_rad`` (same shape), the slew limit allowing
        ``slew_period_s`` of joint motion and the amplitude ramped by ``amplitude``."""
        if targets_rad.ndim == 1:
            return self.safety.filter(targets_rad, slew_period_s, amplitude)
        sent = self.safety.filter(targets_rad.ravel(), slew_period_s, amplitude)
        return sent.reshape(targets_rad.shape)
