"""The drive loop: input -> live gait -> safety -> backend, at a fixed rate, until a stop.

One cycle: poll the input (never blocks), apply its keys, advance the live gait to the robot's
time, pass the targets through the safety layer, send, let ``dt`` pass (the twin steps, hardware
sleeps to the deadline), read the state, then hand the cycle to the observers (display,
telemetry). A stop (quit key, end of script, lost input, a signal) blends the live gait to the
rest pose; the loop ends there and the caller's ``backend.close()`` applies the stop policy.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from snakebot.backends.base import Backend
from snakebot.control.metrics import RunMetrics
from snakebot.control.safety import SafetyLayer
from snakebot.drive.controller import DriveController
from snakebot.drive.sources import InputSource
from snakebot.gaits.live import LiveGait, LiveStatus
from snakebot.types import BodyState, JointCommand, JointState

STOP_GRACE_S = 5.0
"""Longest wait for the live gait to reach the rest pose after its blend should have ended."""


@dataclass(frozen=True)
class DriveCycle:
    """What one drive cycle did, for observers (display, telemetry sinks).

    ``target_rad`` is the live gait's output, ``command_rad`` what the safety layer sent (both
    (N,) rad); ``state`` was read after the command; ``keys`` were applied this cycle.
    """

    cycle: int
    drive_time_s: float
    target_rad: np.ndarray
    command_rad: np.ndarray
    state: JointState
    body: BodyState | None
    status: LiveStatus
    keys: tuple[str, ...]


DriveObserver = Callable[[DriveCycle], None]
StopCheck = Callable[[], str | None]


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
) -> DriveResult:
    """Drive a connected ``backend`` from ``source`` until a stop brings it to the rest pose.

    ``stop_check()`` returns a reason to stop (a signal) or None; it is asked every cycle.
    """
    dt = 1.0 / rate_hz
    state = backend.read_state()
    safety.reset(state.position_rad)
    live.reset()
    live.start(state.position_rad)
    controller.begin()
    metrics.start(state.time_s, backend.body_state())
    start_s = state.time_s
    cycle = 0
    stop_deadline: float | None = None
    while True:
        now = state.time_s - start_s
        keys = tuple(key for key in source.poll(now) if controller.apply(key, now))
        _check_stop(controller, source, stop_check)
        target = live.command(state.time_s, state.position_rad)
        command = safety.filter(target, dt)
        backend.send_command(JointCommand(command))
        backend.advance(dt)
        state = backend.read_state()
        body = backend.body_state()
        metrics.add(command, state, body, dt)
        cycle += 1
        record = DriveCycle(cycle, now, target, command, state, body, live.status(), keys)
        for observer in observers:
            observer(record)
        if controller.stop_reason is not None:
            if live.finished:
                break
            if stop_deadline is None:
                stop_deadline = now + record.status.blend_left_s + STOP_GRACE_S
            elif now > stop_deadline:
                break  # backend.close() still ramps to the safe pose
    summary = metrics.summary(None)
    elapsed = metrics.end_time_s - (metrics.start_time_s or 0.0)
    summary["rate_hz"] = rate_hz
    summary["achieved_rate_hz"] = metrics.cycles / elapsed if elapsed > 0 else rate_hz
    summary["overruns"] = backend.stats.overruns
    summary["stopped_by"] = controller.stop_reason
    summary["keys"] = controller.events
    summary["governed_cycles"] = live.governed_cycles
    summary["interrupted"] = False
    health = getattr(backend, "physics_health", None)  # the twin's physics checks
    if callable(health) and (physics := health()) is not None:
        summary["physics"] = physics
    return DriveResult(summary, controller.stop_reason or "", cycle)


def _check_stop(controller: DriveController, source: InputSource, check: StopCheck | None) -> None:
    if controller.stop_reason is not None:
        return
    reason = check() if check is not None else None
    if reason is not None:
        controller.request_stop(reason)
    elif source.lost is not None:
        controller.request_stop(f"input lost: {source.lost}")
    elif source.exhausted:
        controller.request_stop("end of script")
