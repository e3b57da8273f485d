"""A run's summary computed back from its telemetry CSV (and sidecar): ``snakebot log info``.

The keys follow ``snakebot run --json`` where the file holds what they need. The CSV has every
cycle the loop ran, a run's ramp-out included, so the figures cover the whole log, not only the
scored window. Without the robot's timing counters, ``late_cycles`` counts the periods between
rows longer than 1.5 control periods (on the twin, robot time never runs late).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from snakebot.telemetry.csv_log import TelemetryLog
from snakebot.types import positive_power_w

GRAVITY_M_S2 = 9.81
LATE_FACTOR = 1.5


def nominal_period_s(log: TelemetryLog, sidecar: dict[str, Any] | None) -> float | None:
    """The control period: 1 / the sidecar's rate, else the median period between rows."""
    rate = (sidecar or {}).get("rate_hz")
    if isinstance(rate, int | float) and rate > 0:
        return 1.0 / float(rate)
    periods = np.diff(log.column("time_s"))
    return float(np.median(periods)) if periods.size else None


def com_path(log: TelemetryLog) -> np.ndarray | None:
    """The centre of mass (rows, 3) in m, or None when the log has none (hardware: NaN)."""
    com = np.column_stack([log.column(f"com_{axis}_m") for axis in "xyz"])
    finite = np.isfinite(com).all(axis=1)
    return com if finite.any() and finite.all() else None


def summarize(log: TelemetryLog, sidecar: dict[str, Any] | None) -> dict[str, Any]:
    """The summary of ``log``; ConfigError naming the file if it lacks a needed column."""
    meta = sidecar or {}
    robot = meta.get("robot", {}) if isinstance(meta.get("robot"), dict) else {}
    time_s = log.column("time_s")
    command, position = log.joints("command_rad"), log.joints("position_rad")
    velocity, effort = log.joints("velocity_rad_s"), log.joints("effort_nm")
    rows, joints = command.shape
    duration = float(time_s[-1] - time_s[0]) if rows > 1 else 0.0
    period = nominal_period_s(log, sidecar)
    periods = np.diff(time_s)
    error = command - position
    power = positive_power_w(effort, velocity)
    work = float(np.sum(power[1:] * periods[:, None])) if rows > 1 else 0
    out: dict[str, Any] = {
        "log": log.source,
        "robot": robot.get("name"),
        "command": meta.get("command"),
        "backend": meta.get("backend"),
        "gait": _gait(meta),
        "snakebot_version": meta.get("snakebot_version"),
        "created_utc": meta.get("created_utc"),
        "rows": rows,
        "duration_s": round(duration, 6),
        "joints": joints,
        "rate_hz": meta.get("rate_hz") or (1.0 / period if period else None),
        "achieved_rate_hz": (rows - 1) / duration if duration > 0 else None,
        "late_cycles": int(np.sum(periods > LATE_FACTOR * period)) if period else 0,
        "worst_period_s": float(periods.max()) if periods.size else None,
        "tracking_rms_rad": float(np.sqrt(np.mean(error**2))) if error.size else 0.0,
        "worst_tracking_rad": float(np.abs(error).max()) if error.size else 0.0,
        "worst_tracking_joint": int(np.abs(error).max(axis=0).argmax()) if error.size else None,
        "max_abs_command_rad": float(np.abs(command).max()) if command.size else 0.0,
        "max_abs_effort_nm": float(np.abs(effort).max()) if effort.size else 0.0,
        "positive_work_j": work,
    }
    com = com_path(log)
    if com is None or rows < 2:
        out.update(
            distance_m=None,
            displacement_m=None,
            speed_mps=None,
            heading_deg=None,
            path_length_m=None,
            cost_of_transport=None,
        )
        return out
    dx, dy = (com[-1, :2] - com[0, :2]).tolist()
    distance = math.hypot(dx, dy)
    mass = _mass_kg(robot)
    out.update(
        distance_m=distance,
        displacement_m=[dx, dy],
        speed_mps=distance / duration if duration > 0 else 0.0,
        heading_deg=math.degrees(math.atan2(dy, dx)) if distance > 0 else 0.0,
        path_length_m=float(np.linalg.norm(np.diff(com[:, :2], axis=0), axis=1).sum()),
        cost_of_transport=(work / (mass * GRAVITY_M_S2 * distance))
        if mass and distance > 1e-9
        else None,
    )
    return out


def _gait(meta: dict[str, Any]) -> Any:
    if isinstance(meta.get("gait"), dict):
        return meta["gait"].get("name")
    if isinstance(meta.get("gaits"), list):
        return [g.get("name") for g in meta["gaits"] if isinstance(g, dict)]
    return None


def _mass_kg(robot: dict[str, Any]) -> float | None:
    link = robot.get("link")
    if isinstance(link, dict) and isinstance(link.get("mass_kg"), int | float):
        return float(link["mass_kg"]) * (int(robot.get("joint_count", 0)) + 1)
    return None
