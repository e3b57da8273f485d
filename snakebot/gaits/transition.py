"""Blended transitions between live gaits, and how long a blend must take to stay in the envelope.

A source is what a live gait plays: a ``Track`` (one gait), a ``Hold`` (a fixed pose: the start
pose, the rest pose) or a ``Blend`` of two sources. A blend cross-fades the outgoing source into
the incoming one with a smoothstep weight while both keep playing, so neither stops abruptly.
The straight cross-fade is the shortest path between the two (the joint box is convex, so every
blended pose is inside the limits); its duration is lengthened until the fade's own speed plus
the gaits' speeds fits the joint speed budget (``blend_duration_s``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from snakebot.gaits.base import FloatArray
from snakebot.gaits.live_track import LiveControls, Track

SMOOTHSTEP_PEAK_SLOPE = 1.5
"""Largest slope of 3x^2 - 2x^3 on [0, 1] (at x = 1/2)."""
MAX_NESTING = 3
"""Blends of blends kept playing; deeper, the oldest outgoing pose is frozen (a Hold)."""


def smoothstep(fraction: float) -> float:
    """0..1 with zero slope at both ends: 3x^2 - 2x^3 of x clipped to [0, 1]."""
    x = min(max(fraction, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


class Source(Protocol):
    """Something a live gait plays: advanced by time, read as a pose (N,) in rad."""

    def advanced(self, dt_s: float, setpoint: LiveControls | None) -> Source:
        """This source ``dt_s`` later; ``setpoint`` steers the newest track, None keeps it."""
        ...

    def pose(self) -> FloatArray:
        """Joint targets (N,) in rad now."""
        ...

    def peak_speed_rad_s(self) -> float:
        """An estimate of the fastest joint speed it moves at now, in rad/s."""
        ...


@dataclass(frozen=True)
class Hold:
    """A fixed pose (N,) in rad: the pose the drive started from, or the rest pose."""

    target: FloatArray
    label: str = "hold"

    def advanced(self, dt_s: float, setpoint: LiveControls | None) -> Hold:
        """Itself: a held pose does not move."""
        return self

    def pose(self) -> FloatArray:
        """The held pose."""
        return self.target

    def peak_speed_rad_s(self) -> float:
        """0: it does not move."""
        return 0.0


@dataclass(frozen=True)
class Blend:
    """``outgoing`` fading into ``incoming`` over ``duration_s``; ``elapsed_s`` into it."""

    outgoing: Source
    incoming: Source
    duration_s: float
    elapsed_s: float = 0.0

    @property
    def fraction(self) -> float:
        """How far the blend has gone, 0..1 in time."""
        return min(self.elapsed_s / self.duration_s, 1.0) if self.duration_s > 0 else 1.0

    def advanced(self, dt_s: float, setpoint: LiveControls | None) -> Source:
        """Both sources advanced; the incoming one alone once the blend is complete."""
        incoming = self.incoming.advanced(dt_s, setpoint)
        elapsed = self.elapsed_s + dt_s
        if elapsed >= self.duration_s:
            return incoming
        return Blend(self.outgoing.advanced(dt_s, None), incoming, self.duration_s, elapsed)

    def pose(self) -> FloatArray:
        """(1 - w) * outgoing + w * incoming, w the smoothstep of the fraction."""
        weight = smoothstep(self.fraction)
        if weight <= 0.0:
            return self.outgoing.pose()
        out: FloatArray = (1.0 - weight) * self.outgoing.pose() + weight * self.incoming.pose()
        return out

    def peak_speed_rad_s(self) -> float:
        """The faster of the two sources (the fade's own speed is not included)."""
        return max(self.outgoing.peak_speed_rad_s(), self.incoming.peak_speed_rad_s())


def newest_track(source: Source) -> Track | None:
    """The track the driver steers: the incoming end of the blends, None for a Hold."""
    while isinstance(source, Blend):
        source = source.incoming
    return source if isinstance(source, Track) else None


def newest_blend(source: Source) -> Blend | None:
    """The blend toward the newest source, if one is under way."""
    newest = None
    while isinstance(source, Blend):
        newest, source = source, source.incoming
    return newest


def depth(source: Source) -> int:
    """How many blends are nested on the outgoing side."""
    count = 0
    while isinstance(source, Blend):
        count, source = count + 1, source.outgoing
    return count


def blend_into(
    current: Source,
    incoming: Source,
    *,
    duration_s: float,
    speed_budget_rad_s: float,
    setpoint: LiveControls | None,
) -> Blend:
    """A blend from ``current`` to ``incoming``, lasting at least ``duration_s``, longer when
    the joint speed budget (rad/s) needs it; blends nested too deep freeze their oldest pose."""
    if depth(current) >= MAX_NESTING:
        current = Hold(current.pose(), "frozen")
    needed = blend_duration_s(
        current,
        incoming,
        duration_s=duration_s,
        speed_budget_rad_s=speed_budget_rad_s,
        setpoint=setpoint,
    )
    return Blend(current, incoming, max(duration_s, needed))


def blend_duration_s(
    outgoing: Source,
    incoming: Source,
    *,
    duration_s: float,
    speed_budget_rad_s: float,
    setpoint: LiveControls | None,
    samples: int = 12,
) -> float:
    """The shortest blend in s that keeps every joint under ``speed_budget_rad_s``.

    A blended joint moves at most max(v_out, v_in) + w' * |in - out|, and the smoothstep's
    slope peaks at 1.5 / T, so T >= 1.5 * D / (budget - v) with D the largest gap between the
    two sources over the blend (sampled by playing both forward ``duration_s``). When the
    gaits alone use up more than 3/4 of the budget, a quarter is kept for the fade.
    """
    gap = 0.0
    out, inc = outgoing, incoming
    step = duration_s / samples if duration_s > 0 else 0.0
    for _ in range(samples + 1):
        gap = max(gap, float(np.max(np.abs(inc.pose() - out.pose()))))
        if step == 0.0:
            break
        out, inc = out.advanced(step, None), inc.advanced(step, setpoint)
    moving = max(outgoing.peak_speed_rad_s(), incoming.peak_speed_rad_s())
    spare = max(speed_budget_rad_s - moving, 0.25 * speed_budget_rad_s)
    return SMOOTHSTEP_PEAK_SLOPE * gap / spare if math.isfinite(gap) else math.inf
