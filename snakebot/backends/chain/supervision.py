"""Noticing servos that stopped following the goals, and bringing them back without a jump.

Nothing here touches the bus. :class:`TrackingMonitor` looks at what the cycle already reads
(Present Position) and what it already sends (Goal Position) at the slow rate; :class:`CatchUp`
slews the goals from where a stopped chain stands back to the commands; :class:`TripCounter`
decides when Bus Watchdog trips come too often to recover from.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class TrackingLimits:
    """When a joint counts as no longer following its goals, and how many watchdog trips to bear.

    A joint is flagged when its Present Position has stayed within ``still_rad`` for ``window_s``
    while its Goal Position travelled at least ``min_travel_rad`` and it now sits at least
    ``min_error_rad`` from its goal. The defaults suit XL430/XC430/XM430 chains: a loaded joint
    that lags, one pushing against an obstacle but still moving (more than 0.35° in a second), or
    one on soft gains held by friction a little off its goal (as gain tuning tries) is never
    flagged; a joint that does not move at all for a second while a gait sweeps its goal through
    half a radian and leaves it 20° away is (a servo that lost torque, a jammed joint, readings
    that froze). A tripped Bus Watchdog is found sooner, by reading its register.
    ``max_watchdog_trips`` trips within ``trip_window_s`` are recovered (clear, re-arm, catch up);
    one more stops the run.
    """

    still_rad: float = 0.006  # 4 ticks of a 4096-tick servo
    window_s: float = 1.0
    min_travel_rad: float = 0.5
    min_error_rad: float = 0.35
    max_watchdog_trips: int = 3
    trip_window_s: float = 10.0

    def __post_init__(self) -> None:
        for name in ("still_rad", "window_s", "min_travel_rad", "min_error_rad", "trip_window_s"):
            value = getattr(self, name)
            if not (value > 0 and math.isfinite(value)):
                raise ValueError(f"TrackingLimits.{name} must be a positive number, got {value}")
        if self.max_watchdog_trips < 0:
            raise ValueError(f"max_watchdog_trips must be >= 0, got {self.max_watchdog_trips}")


@dataclass(frozen=True)
class Stall:
    """A joint the monitor flagged: where it stands and where it was told to go (ticks)."""

    joint: int
    present_ticks: int
    goal_ticks: int
    still_for_s: float
    travel_ticks: int


class TrackingMonitor:
    """Per-joint bookkeeping of "the reading stands still while the goal moves" (ticks, seconds).

    ``check`` is called at the slow rate with the latest Present and Goal Position of every joint
    (head to tail) and returns the joints that stood still too long; plain ints, no numpy.
    """

    def __init__(self, limits: TrackingLimits, joint_count: int, rad_per_tick: float) -> None:
        self.limits = limits
        self._still = max(1, round(limits.still_rad / rad_per_tick))
        self._travel = max(1, round(limits.min_travel_rad / rad_per_tick))
        self._error = max(1, round(limits.min_error_rad / rad_per_tick))
        self._n = joint_count
        self._anchor: list[int | None] = [None] * joint_count
        self._since = [0.0] * joint_count
        self._moved = [0] * joint_count
        self._last_goal = [0] * joint_count

    def reset(self) -> None:
        """Forget every joint's history (after a recovery, or when goals start again)."""
        self._anchor = [None] * self._n

    def check(self, now_s: float, present: Sequence[int], goals: Sequence[int]) -> list[Stall]:
        """The joints whose reading stood still for the window while their goals travelled."""
        stalls = []
        window = self.limits.window_s
        for j in range(self._n):
            p, g, anchor = present[j], goals[j], self._anchor[j]
            if anchor is None or abs(p - anchor) > self._still:
                self._anchor[j], self._since[j], self._moved[j] = p, now_s, 0
                self._last_goal[j] = g
                continue
            self._moved[j] += abs(g - self._last_goal[j])
            self._last_goal[j] = g
            still_for = now_s - self._since[j]
            if still_for >= window and self._moved[j] >= self._travel and abs(g - p) >= self._error:
                stalls.append(Stall(j, p, g, still_for, self._moved[j]))
        return stalls


class CatchUp:
    """Goals slewed from a stopped pose to the commands at ``max_ticks_per_s``; done when caught up.

    After a Bus Watchdog trip the servos stand where they stopped while the commands moved on;
    sending the commands at once would jump them there at full speed.
    """

    def __init__(self, start_ticks: Sequence[int], max_ticks_per_s: float, now_s: float) -> None:
        self._last = list(start_ticks)
        self._rate = max_ticks_per_s
        self._t = now_s
        self.done = False

    def limit(self, goals: list[int], now_s: float) -> list[int]:
        """The goals to send now (ticks, one per joint)."""
        step = max(1, int(self._rate * max(now_s - self._t, 0.0)))
        self._t = now_s
        out, caught = [], True
        for last, goal in zip(self._last, goals, strict=True):
            if goal > last + step:
                goal, caught = last + step, False
            elif goal < last - step:
                goal, caught = last - step, False
            out.append(goal)
        self._last = out
        self.done = caught
        return out


class TripCounter:
    """Bus Watchdog trips within the last ``window_s`` seconds."""

    def __init__(self, window_s: float) -> None:
        self.window_s = window_s
        self._times: deque[float] = deque()
        self.total = 0

    def add(self, now_s: float) -> int:
        """Record a trip at ``now_s``; the number of trips within the window, this one included."""
        self._times.append(now_s)
        self.total += 1
        while self._times and now_s - self._times[0] > self.window_s:
            self._times.popleft()
        return len(self._times)
