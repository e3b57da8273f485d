"""The run so far between two status messages: rate, tracking and speed over the interval, and
when a channel sent at its own rate is next due. Shared by the Foxglove stream and the ROS 2
recording, so their metrics agree."""

from __future__ import annotations

import math

import numpy as np


def next_due(due: float, time_s: float, rate_hz: float) -> float:
    """When a channel sent at ``time_s`` (it was due at ``due``) is next due: one period after
    ``due``, so a 30 Hz channel averages 30 Hz on a 100 Hz loop (one period after ``time_s``
    would round every wait up to whole cycles: 25 Hz), unless that is already past."""
    period = 1.0 / rate_hz
    following = due + period
    return following if following > time_s else time_s + period


class RunWindow:
    """Rate (Hz), tracking RMS (rad) and speed (m/s) over the interval since ``restart``."""

    def __init__(self) -> None:
        self.restart()

    def restart(self) -> None:
        """Start a new interval."""
        self._cycles = 0
        self._squares = 0.0
        self._count = 0
        self._start: tuple[float, np.ndarray | None] | None = None
        self._end: tuple[float, np.ndarray | None] | None = None

    def add(self, time_s: float, error: np.ndarray, com: np.ndarray | None) -> None:
        """One cycle at robot time ``time_s``: its tracking error (N,) rad, its centre of mass
        (3,) m or None."""
        if self._start is None:
            self._start = (time_s, com)
        self._end = (time_s, com)
        self._cycles += 1
        self._squares += float(error @ error)
        self._count += error.size

    def rate_hz(self) -> float | None:
        """Cycles per second of robot time over the interval; None before two cycles."""
        if self._start is None or self._end is None or self._end[0] <= self._start[0]:
            return None
        return (self._cycles - 1) / (self._end[0] - self._start[0])

    def tracking_rms(self) -> float:
        """RMS of every joint's tracking error over the interval, rad (0 before a cycle)."""
        return math.sqrt(self._squares / self._count) if self._count else 0.0

    def speed_mps(self) -> float | None:
        """Ground speed of the centre of mass over the interval, m/s; None without a CoM."""
        if self._start is None or self._end is None or self._end[0] <= self._start[0]:
            return None
        (t0, c0), (t1, c1) = self._start, self._end
        if c0 is None or c1 is None:
            return None
        return float(np.hypot(*(c1[:2] - c0[:2]))) / (t1 - t0)
