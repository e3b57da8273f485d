"""The node's control cycle: the inbox's commands -> gait -> safety -> backend, until a stop.

The same shape as the drive loop (snakebot.drive.run): every cycle the driver takes what the
ROS callbacks left (snakebot.ros2.commands), then the shared control cycle
(snakebot.control.loop.CycleLoop) makes the targets, passes them through the safety layer,
sends them, lets a period pass and reads the state; the node's publishers are observers of
each cycle's record. A stop (a signal, a command timeout) blends the gait to the rest pose;
the loop ends there and the caller's ``backend.close()`` applies the stop policy. Nothing here
imports rclpy.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from snakebot.backends.base import Backend
from snakebot.control.cycle import CycleObserver, CycleSchedule, GaitCycle, StopCheck
from snakebot.control.loop import CycleLoop
from snakebot.control.metrics import RunMetrics
from snakebot.control.safety import SafetyLayer
from snakebot.control.summary import run_summary
from snakebot.drive.run import STOP_GRACE_S
from snakebot.ros2.commands import CommandDriver


@dataclass(frozen=True)
class ServeResult:
    """How the node's control cycle ended: the summary (``snakebot run``'s keys plus the
    node's), why it stopped, and the cycles it ran."""

    summary: dict[str, object]
    stopped_by: str
    cycles: int


def serve_commands(
    backend: Backend,
    driver: CommandDriver,
    safety: SafetyLayer,
    *,
    rate_hz: float,
    metrics: RunMetrics,
    observers: Sequence[CycleObserver] = (),
    stop_check: StopCheck | None = None,
) -> ServeResult:
    """Run the control cycle on a connected ``backend`` at ``rate_hz`` until a stop brings the
    snake to the rest pose.

    ``stop_check()`` (a signal) is asked every cycle, the driver's watchdog too; each of
    ``observers`` sees every cycle's record (the publishers). Raises the backend's ConfigError
    for a rate it cannot hold before the first command, and what the cycle raises.
    """
    backend.check_rate(rate_hz)
    schedule = CycleSchedule(rate_hz)  # open-ended; the live gait blends in and out itself
    gait = driver.gait
    loop = CycleLoop(backend, GaitCycle([gait], safety), schedule, metrics, observers=observers)
    loop.start()
    gait.live.start(loop.state.position_rad)  # held until the first command
    stop_deadline: float | None = None
    while True:
        now = loop.elapsed_s
        driver.apply(now)
        if driver.stop_reason is None and stop_check is not None:
            reason = stop_check()
            if reason is not None:
                driver.stop(reason)
        loop.step(now, 1.0, scored=True)
        if driver.stop_reason is not None:
            if gait.live.finished:
                break
            if stop_deadline is None:
                stop_deadline = now + gait.live.status().blend_left_s + STOP_GRACE_S
            elif now > stop_deadline:
                break  # backend.close() still ramps to the safe pose
    summary = run_summary(metrics, backend, rate_hz=rate_hz, gait_period_s=None, interrupted=False)
    inbox = driver.inbox
    summary["stopped_by"] = driver.stop_reason
    summary["commands"] = inbox.received
    summary["refused_commands"] = inbox.refused
    summary["command_timeouts"] = driver.timeouts
    summary["governed_cycles"] = gait.live.governed_cycles
    return ServeResult(summary, driver.stop_reason or "", loop.cycle)
