"""What the control loops write a cycle to: the CSV log, Foxglove, MCAP, or several at once."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np


class CycleLog(Protocol):
    """A per-cycle telemetry sink with the CSV writer's ``write``; ``rows`` counts cycles."""

    @property
    def rows(self) -> int:
        """Cycles written so far."""
        ...

    def write(
        self,
        time_s: float,
        cycle: int,
        command: np.ndarray,
        position: np.ndarray,
        velocity: np.ndarray,
        effort: np.ndarray,
        com: np.ndarray | None,
        imu: tuple[np.ndarray, np.ndarray | None] | None = None,
    ) -> None:
        """Take one cycle: robot time (s), its number, (N,) command/position rad, velocity
        rad/s, effort N m, the centre of mass (3,) m or None (hardware), and the head IMU
        (quaternion (4,), gyro (3,) rad/s or None) or None."""
        ...

    def close(self) -> None:
        """Flush and release; idempotent."""
        ...


class TelemetryTee:
    """Hands every cycle to several sinks in order; ``rows`` are the first sink's.

    A sink that raises stops the cycle there (the runner then drops the whole tee from its
    ramp-out); ``close`` closes all of them and raises the first failure after trying each.
    """

    def __init__(self, sinks: Sequence[CycleLog]) -> None:
        if not sinks:
            raise ValueError("a telemetry tee needs at least one sink")
        self.sinks = tuple(sinks)

    @property
    def rows(self) -> int:
        """Cycles the first sink took."""
        return self.sinks[0].rows

    def write(
        self,
        time_s: float,
        cycle: int,
        command: np.ndarray,
        position: np.ndarray,
        velocity: np.ndarray,
        effort: np.ndarray,
        com: np.ndarray | None,
        imu: tuple[np.ndarray, np.ndarray | None] | None = None,
    ) -> None:
        """Write the cycle to every sink (see :meth:`CycleLog.write`)."""
        for sink in self.sinks:
            sink.write(time_s, cycle, command, position, velocity, effort, com, imu)

    def close(self) -> None:
        """Close every sink; the first failure is raised once all were tried."""
        failure: BaseException | None = None
        for sink in self.sinks:
            try:
                sink.close()
            except Exception as exc:
                failure = failure or exc
        if failure is not None:
            raise failure


def combine(sinks: Sequence[CycleLog | None]) -> CycleLog | None:
    """None, the one sink, or a tee of the sinks that are not None."""
    present = [sink for sink in sinks if sink is not None]
    if not present:
        return None
    return present[0] if len(present) == 1 else TelemetryTee(present)
