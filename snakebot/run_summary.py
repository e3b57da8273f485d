"""RunSummary: what one gait run measured, typed and frozen; ``to_dict()`` is ``run --json``."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

__all__ = ["RunSummary"]


def _frozen(mapping: Mapping[str, Any]) -> Mapping[str, Any]:
    return MappingProxyType(dict(mapping))


@dataclass(frozen=True)
class RunSummary:
    """One run of a gait: where the snake went, how well the joints tracked, how fast it ran.

    Distances in m, angles in degrees, times in s, work in J. The distance-based fields
    (``distance_m`` ... ``cost_of_transport``) are None on a backend that cannot measure the
    body (hardware). ``cycles`` (gait cycles) is None for a gait without a period.
    ``backend_stats`` holds the backend's own counters (servo temperature, clipped commands,
    ...); ``extra`` holds backend-specific results printed beside the others (a mass-spring
    body's travel angle). ``log`` is the telemetry CSV, ``log_rows`` its data rows.
    ``physics`` is the twin's physics health (penetration, airborne and upside-down fractions,
    chatter, energy, stall; warnings past the thresholds in docs/physics.md) and, with the fuller
    servo model, its electrical figures; None on a backend without them (hardware).
    """

    robot: str
    gait: str
    backend: str
    duration_s: float
    joints: int
    body_length_m: float
    control_cycles: int
    cycles: float | None
    tracking_rms_rad: float
    max_abs_command_rad: float
    positive_work_j: float
    distance_m: float | None
    displacement_m: tuple[float, float] | None
    speed_mps: float | None
    heading_deg: float | None
    turn_deg: float | None
    body_lengths_per_cycle: float | None
    cost_of_transport: float | None
    rate_hz: float
    achieved_rate_hz: float
    overruns: int
    interrupted: bool
    backend_stats: Mapping[str, float] = field(default_factory=lambda: _frozen({}))
    extra: Mapping[str, Any] = field(default_factory=lambda: _frozen({}))
    log: str | None = None
    log_rows: int = 0
    video: str | None = None
    physics: Mapping[str, Any] | None = None

    @classmethod
    def from_run(
        cls,
        *,
        robot: str,
        gait: str,
        backend: str,
        metrics: Mapping[str, Any],
        extra: Mapping[str, Any] | None = None,
        log: str | None = None,
        log_rows: int = 0,
    ) -> RunSummary:
        """From the runner's summary dict (snakebot.control.runner.RunResult.summary)."""
        displacement = metrics.get("displacement_m")
        return cls(
            robot=robot,
            gait=gait,
            backend=backend,
            duration_s=float(metrics["duration_s"]),
            joints=int(metrics["joints"]),
            body_length_m=float(metrics["body_length_m"]),
            control_cycles=int(metrics["control_cycles"]),
            cycles=_optional(metrics.get("cycles")),
            tracking_rms_rad=float(metrics["tracking_rms_rad"]),
            max_abs_command_rad=float(metrics["max_abs_command_rad"]),
            positive_work_j=float(metrics["positive_work_j"]),
            distance_m=_optional(metrics.get("distance_m")),
            displacement_m=None
            if displacement is None
            else (float(displacement[0]), float(displacement[1])),
            speed_mps=_optional(metrics.get("speed_mps")),
            heading_deg=_optional(metrics.get("heading_deg")),
            turn_deg=_optional(metrics.get("turn_deg")),
            body_lengths_per_cycle=_optional(metrics.get("body_lengths_per_cycle")),
            cost_of_transport=_optional(metrics.get("cost_of_transport")),
            rate_hz=float(metrics["rate_hz"]),
            achieved_rate_hz=float(metrics["achieved_rate_hz"]),
            overruns=int(metrics["overruns"]),
            interrupted=bool(metrics["interrupted"]),
            backend_stats=_frozen(metrics.get("backend_stats", {})),
            extra=_frozen(extra or {}),
            log=log,
            log_rows=log_rows,
            physics=None if metrics.get("physics") is None else _frozen(metrics["physics"]),
        )

    def to_dict(self) -> dict[str, Any]:
        """The JSON object ``snakebot run --json`` prints: every field (``extra`` spread at the
        top level, ``displacement_m`` as a list); ``log``/``log_rows``/``video`` only when set."""
        out: dict[str, Any] = {
            "robot": self.robot,
            "gait": self.gait,
            "backend": self.backend,
            "duration_s": self.duration_s,
            "joints": self.joints,
            "body_length_m": self.body_length_m,
            "control_cycles": self.control_cycles,
            "cycles": self.cycles,
            "tracking_rms_rad": self.tracking_rms_rad,
            "max_abs_command_rad": self.max_abs_command_rad,
            "positive_work_j": self.positive_work_j,
            "distance_m": self.distance_m,
            "displacement_m": None if self.displacement_m is None else list(self.displacement_m),
            "speed_mps": self.speed_mps,
            "heading_deg": self.heading_deg,
            "turn_deg": self.turn_deg,
            "body_lengths_per_cycle": self.body_lengths_per_cycle,
            "cost_of_transport": self.cost_of_transport,
            "rate_hz": self.rate_hz,
            "achieved_rate_hz": self.achieved_rate_hz,
            "overruns": self.overruns,
            "backend_stats": dict(self.backend_stats),
            "interrupted": self.interrupted,
            **self.extra,
        }
        if self.log is not None:
            out["log"] = self.log
            out["log_rows"] = self.log_rows
        if self.video is not None:
            out["video"] = self.video
        if self.physics is not None:
            out["physics"] = dict(self.physics)
        return out


def _optional(value: Any) -> float | None:
    return None if value is None else float(value)
