"""The summary of a run, assembled in one place for ``run_gait`` and the drive loop.

What every run reports: the metrics of its scored cycles (snakebot.control.metrics: distance,
tracking, work...), the rate asked for and the rate achieved in robot time, the backend's
overruns and counters, whether Ctrl-C ended it, and the twin's physics checks where the backend
runs them (``ChecksPhysics``). ``snakebot run`` and ``snakebot drive`` print these same keys;
each adds its own (the drive: how it stopped, its keys).
"""

from __future__ import annotations

from snakebot.backends.base import Backend
from snakebot.backends.capabilities import ChecksPhysics
from snakebot.control.metrics import RunMetrics


def run_summary(
    metrics: RunMetrics,
    backend: Backend,
    *,
    rate_hz: float,
    gait_period_s: float | None,
    interrupted: bool,
) -> dict[str, object]:
    """The summary dict (JSON-ready) of a run that ended on ``backend``.

    ``gait_period_s`` (None: not periodic, or live) counts gait cycles; ``achieved_rate_hz``
    is scored cycles per second of robot time over the scored window (``rate_hz`` before one
    has passed). ``physics`` is there only where the backend checks its physics and found
    something to report.
    """
    summary = metrics.summary(gait_period_s)
    elapsed = metrics.end_time_s - (metrics.start_time_s or 0.0)
    summary["rate_hz"] = rate_hz
    summary["achieved_rate_hz"] = metrics.cycles / elapsed if elapsed > 0 else rate_hz
    summary["overruns"] = backend.stats.overruns
    summary["backend_stats"] = dict(backend.stats.extra)
    summary["interrupted"] = interrupted
    if isinstance(backend, ChecksPhysics) and (physics := backend.physics_health()) is not None:
        summary["physics"] = physics  # the twin's physics checks
    return summary
