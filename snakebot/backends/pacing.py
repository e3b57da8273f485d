"""Real-time pacing shared by backends whose time is the wall clock."""

from __future__ import annotations

import time
from collections.abc import Callable

from snakebot.types import CycleStats


class Pacer:
    """Sleeps to fixed deadlines; a late cycle counts as an overrun and restarts the schedule.

    Restarting (instead of catching up) means a rate the hardware cannot sustain simply runs as
    fast as it can, which is what a servo chain wants: no burst of back-to-back commands.
    """

    def __init__(
        self,
        stats: CycleStats,
        *,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        self._stats = stats
        self._clock = clock
        self._sleep = sleep
        self._deadline: float | None = None
        self.start_s = clock()

    def now_s(self) -> float:
        """Seconds since the pacer was created."""
        return self._clock() - self.start_s

    def wait(self, dt_s: float) -> None:
        """Return at the next deadline, ``dt_s`` after the previous one."""
        now = self._clock()
        deadline = (self._deadline if self._deadline is not None else now) + dt_s
        remaining = deadline - now
        if remaining > 0:
            self._sleep(remaining)
            self._deadline = deadline
        else:
            self._stats.overruns += 1
            self._stats.worst_lateness_s = max(self._stats.worst_lateness_s, -remaining)
            self._deadline = now
