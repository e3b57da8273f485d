"""The drive loop: input -> live gait -> safety -> backend, at a fixed rate, until a stop.

One cycle: poll the input (never blocks), apply a few of its keys (snakebot.drive.gate: a
paste is dropped, not played out), then the control cycle every loop
shares (snakebot.control.loop): advance the live gait to the robot's time, pass the targets
through the safety layer, send, let a period pass (the twin steps, hardware sleeps to the
deadline), read the state; then hand the cycle's record to the observers (display, telemetry).
A stop (quit key, end of script, lost input, a signal) blends the live gait to the rest pose;
the loop ends there and the caller's ``backend.close()`` applies the stop policy.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from snakebot.backends.base import Backend
from snakebot.control.cycle import CycleRecord, CycleSchedule, GaitCycle, StopCheck
from snakebot.control.loop import CycleLoop
from snakebot.control.metrics import RunMetrics
from snakebot.control.safety import SafetyLayer
from snakebot.control.summary import run_summary
from snakebot.drive.controller import DriveController
from snakebot.drive.gate import BACKLOG, KeyGate
from snakebot.drive.sources import InputSource
from snakebot.gaits.live import LiveGait, LiveStatus

STOP_GRACE_S = 5.0
"""Longest wait for the live gait to reach the rest pose after its blend should have ended."""


@dataclass(frozen=True)
class DriveCycle(CycleRecord):
    """What one drive cycle did, for observers (display, telemetry sinks): the control cycle's
    record (snakebot.control.cycle.CycleRecord) plus the live gait's ``status`` after it and the
    ``keys`` applied this cycle. ``drive_time_s`` is the record's gait time."""

    status: LiveStatus
    keys: tuple[str, ...]

    @property
    def drive_time_s(self) -> float:
        """Robot seconds since the drive started, when the cycle's targets were made."""
        return self.gait_time_s


DriveObserver = Callable[[DriveCycle], None]


@dataclass(frozen=True)
class DriveResult:
    """How a drive ended: the summary (``snakebot run``'s keys plus the drive's own)."""

    summary: dict[str, object]
    stopped_by: str
    cycles: int


def run_drive(
    backend: Backend,
    live: LiveGait,
    safety: SafetyLayer,
    controller: DriveController,
    source: InputSource,
    *,
    rate_hz: float,
    metrics: RunMetrics,
    observers: Sequence[DriveObserver] = (),
    stop_check: StopCheck | None = None,
    gate: KeyGate | None = None,
) -> DriveResult:
    """Drive a connected ``backend`` from ``source`` until a stop brings it to the rest pose.

    ``stop_check()`` returns a reason to stop (a signal) or None; it is asked every cycle.
    ``gate`` bounds the keys a cycle applies (default: a KeyGate that drops a flood from a live
    source, never the controller's stop and halt keys, and nothing from a script).
    """
    backend.check_rate(rate_hz)  # a servo bus that cannot hold the rate refuses it here
    if gate is None:
        gate = KeyGate(controller.settles, backlog=BACKLOG if source.live else None)
    schedule = CycleSchedule(rate_hz)  # open-ended; the live gait blends in and out itself
    loop = CycleLoop(backend, GaitCycle([live], safety), schedule, metrics)
    loop.start()
    live.start(loop.state.position_rad)
    controller.begin()
    stop_deadline: float | None = None
    while True:
        now = loop.elapsed_s
        dropped = gate.dropped
        keys = tuple(key for key in gate.admit(source.poll(now), now) if controller.apply(key, now))
        if gate.dropped != dropped:
            controller.notice = gate.notice
        _check_stop(controller, source, stop_check, keys_waiting=gate.waiting > 0)
        done = loop.step(now, 1.0, scored=True)
        status = live.status()
        record = DriveCycle(**vars(done), status=status, keys=keys)
        for observer in observers:
            observer(record)
        if controller.stop_reason is not None:
            if live.finished:
                break
            if stop_deadline is None:
                stop_deadline = now + status.blend_left_s + STOP_GRACE_S
            elif now > stop_deadline:
                break  # backend.close() still ramps to the safe pose
    summary = run_summary(metrics, backend, rate_hz=rate_hz, gait_period_s=None, interrupted=False)
    summary["stopped_by"] = controller.stop_reason
    summary["keys"] = controller.events
    summary["dropped_keys"] = gate.dropped
    summary["governed_cycles"] = live.governed_cycles
    return DriveResult(summary, controller.stop_reason or "", loop.cycle)


def _check_stop(
    controller: DriveController,
    source: InputSource,
    check: StopCheck | None,
    *,
    keys_waiting: bool,
) -> None:
    if controller.stop_reason is not None:
        return
    reason = check() if check is not None else None
    if reason is not None:
        controller.request_stop(reason)
    elif source.lost is not None:
        controller.request_stop(f"input lost: {source.lost}")
    elif source.exhausted and not keys_waiting:
        controller.request_stop("end of script")
