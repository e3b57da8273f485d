"""What leaves a control loop: each cycle's record, to the CSV log, Foxglove, MCAP, or several.

Every sink is a :class:`~snakebot.control.cycle.CycleSink`: an observer of the cycle's
``CycleRecord`` that counts its ``rows`` and can be closed. A sink reads the record's fields
it shows, so a new channel is one record field plus the sinks that choose to show it.
"""

from __future__ import annotations

from collections.abc import Sequence

from snakebot.control.cycle import CycleRecord, CycleSink

__all__ = ["CycleSink", "TelemetryTee", "combine"]


class TelemetryTee:
    """Hands every cycle's record to several sinks in order; ``rows`` are the first sink's.

    A sink that raises stops the cycle there (the runner then drops the whole tee from its
    ramp-out); ``close`` closes all of them and raises the first failure after trying each.
    """

    def __init__(self, sinks: Sequence[CycleSink]) -> None:
        if not sinks:
            raise ValueError("a telemetry tee needs at least one sink")
        self.sinks = tuple(sinks)

    @property
    def rows(self) -> int:
        """Cycles the first sink took."""
        return self.sinks[0].rows

    def __call__(self, record: CycleRecord) -> None:
        """Hand the record to every sink."""
        for sink in self.sinks:
            sink(record)

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


def combine(sinks: Sequence[CycleSink | None]) -> CycleSink | None:
    """None, the one sink, or a tee of the sinks that are not None."""
    present = [sink for sink in sinks if sink is not None]
    if not present:
        return None
    return present[0] if len(present) == 1 else TelemetryTee(present)
