"""The backend readings the drive display and Foxglove show."""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from snakebot.backends.base import Backend
from snakebot.backends.capabilities import OnBus, ReportsHealth


def backend_readings(
    backend: Backend,
) -> tuple[Callable[[], Mapping[str, np.ndarray]], Callable[[], tuple[str, ...]]]:
    """(health, alerts) callables for the display: the backend's slow readings where it
    reports them (``ReportsHealth``: the Dynamixel backend's ``temperature_c`` (N,), ...; none
    otherwise) and what went wrong so far (clipped commands, Bus Watchdog re-arms, and on a
    servo bus (``OnBus``) its retries and the servos raising the alert bit)."""
    bus = backend.bus if isinstance(backend, OnBus) else None

    def alerts() -> tuple[str, ...]:
        extra = backend.stats.extra
        found = [
            f"{key.replace('_', ' ')} {int(extra[key])}"
            for key in ("clipped_commands", "watchdog_rearms")
            if extra.get(key)
        ]
        if bus is not None:
            retries = sum(bus.retry_counts.values()) + bus.group_retries
            found += [f"retries {retries}"] if retries else []
            for i in sorted(bus.alerts):  # Alert bit (P2), or a P1 status byte's alarms
                bits = bus.conditions.get(i, 0)
                names = [n for n in bus.family.status_errors(bits) if n != "alert"]
                found.append(f"{', '.join(names)}: servo {i}" if names else f"alert bit: servo {i}")
        return tuple(found)

    if isinstance(backend, ReportsHealth):
        return backend.health, alerts
    return _no_health, alerts


def _no_health() -> Mapping[str, np.ndarray]:
    return {}
