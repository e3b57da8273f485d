"""The step-by-step control cycle on any backend: command, send, let time pass, read, record.

``run_gait`` and the live drive loop both step a ``CycleLoop``; the batched tuning engine runs
the same ``GaitCycle`` and ``CycleSchedule`` on ``mujoco.batch`` (snakebot.tuning.engine).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from snakebot.backends.base import Backend
from snakebot.backends.capabilities import SensesBody
from snakebot.control.cycle import (
    CycleHook,
    CycleObserver,
    CycleRecord,
    CycleSchedule,
    GaitCycle,
)
from snakebot.control.metrics import RunMetrics, cycle_work_j
from snakebot.types import JointCommand, JointState


class CycleLoop:
    """One run's cycles on a connected backend, and which parts still take part.

    Everything that leaves the loop leaves as each cycle's ``CycleRecord``: to ``metrics``
    (None: not kept; it accounts the scored cycles), then to the observers in order (the
    telemetry sinks among them: snakebot.telemetry.sink), then ``on_cycle(cycle, gait_time_s)``
    runs; ``step`` returns the record.

    ``stage`` names the part running when an exception leaves ``step`` ("gait", "safety",
    "backend", "metrics", "observer", "hook"); ``leave_out`` drops a failed part from the cycles
    that follow (the runner's ramp-out): the one observer that raised, the others go on.
    """

    def __init__(
        self,
        backend: Backend,
        cycle: GaitCycle,
        schedule: CycleSchedule,
        metrics: RunMetrics | None,
        *,
        on_cycle: CycleHook | None = None,
        observers: Sequence[CycleObserver] = (),
        read_body: bool = True,
    ) -> None:
        self.backend, self.gaits, self.schedule, self.metrics = backend, cycle, schedule, metrics
        self.on_cycle, self.observers = on_cycle, tuple(observers)
        self.body_sensor = backend if read_body and isinstance(backend, SensesBody) else None
        """The backend where it measures the body (COM, head orientation) and ``read_body``
        asks for it every cycle, else None (a learning env reads it at its policy steps)."""
        self.state: JointState = backend.read_state()
        self.start_s = self.state.time_s
        self.target: np.ndarray = self.state.position_rad.copy()  # the gait's last good target
        self.command: np.ndarray = self.state.position_rad.copy()  # the last command sent
        self.use_gait = True
        self.cycle = 0
        self.stage = "gait"
        self._last_period_s: float | None = None
        self._observing = 0

    def start(self) -> None:
        """Reset the gaits and the safety layer to the measured pose; open the scored window."""
        self.gaits.reset(self.state.position_rad)
        if self.metrics is not None:
            sensor = self.body_sensor
            body = None if sensor is None else sensor.body_state()
            self.metrics.start(self.state.time_s, body, self.schedule.period_s)

    @property
    def elapsed_s(self) -> float:
        """Robot time since the run started."""
        return self.state.time_s - self.start_s

    def gait_step(self) -> CycleRecord:
        """One scored gait cycle now: the gait's targets at the robot time since the start,
        ramped in as the schedule ramps (``run_gait``'s gait cycles, a learning env's)."""
        gait_time = self.state.time_s - self.start_s
        return self.step(gait_time, self.schedule.ramp_in(gait_time), scored=True)

    def step(self, gait_time_s: float, amplitude: float, scored: bool) -> CycleRecord:
        """One cycle with the targets of ``gait_time_s`` at ``amplitude``; scored cycles count
        in the metrics. Returns the cycle's record (the metrics and observers have seen it)."""
        backend, schedule = self.backend, self.schedule
        self.stage = "gait"
        before = self.state
        if self.use_gait:
            target = self.gaits.targets(gait_time_s, before.position_rad)
        else:
            target = self.target
        self.stage = "safety"
        slew_s = schedule.slew_period_s(self.cycle, self._last_period_s)
        command = self.gaits.commands(target, slew_s, amplitude)
        self.target, self.command = target, command
        self.stage = "backend"
        overruns = backend.stats.overruns
        backend.send_command(JointCommand(command))
        backend.advance(schedule.period_s)
        self.state = state = backend.read_state()
        body = None if self.body_sensor is None else self.body_sensor.body_state()
        self.cycle += 1
        period = state.time_s - before.time_s
        self._last_period_s = period
        elapsed = state.time_s - self.start_s
        record = CycleRecord(
            cycle=self.cycle,
            gait_time_s=gait_time_s,
            target_rad=target,
            command_rad=command,
            state=state,
            body=body,
            amplitude=amplitude,
            scored=scored,
            period_s=period,
            overrun=backend.stats.overruns != overruns,
            achieved_rate_hz=self.cycle / elapsed if elapsed > 0 else schedule.rate_hz,
            work_j=cycle_work_j(before, state),
        )
        self.stage = "metrics"
        if self.metrics is not None:
            self.metrics(record)
        self.stage = "observer"
        for index, observer in enumerate(self.observers):
            self._observing = index
            observer(record)
        self.stage = "hook"
        if self.on_cycle is not None:
            self.on_cycle(self.cycle, gait_time_s)
        return record

    def leave_out(self, stage: str) -> None:
        """Drop the part that failed from the cycles that follow."""
        if stage in ("gait", "safety"):
            self.use_gait = False  # hold the last target the safety layer accepted
        elif stage == "observer":  # the one that raised; the others (the log) go on
            index = self._observing
            self.observers = self.observers[:index] + self.observers[index + 1 :]
        elif stage == "hook":
            self.on_cycle = None
