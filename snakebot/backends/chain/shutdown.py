"""The stop ramp: from wherever the chain is to the safe pose, smoothly, before hold or limp."""

from __future__ import annotations

import math

import numpy as np

from snakebot.config.schema import RobotConfig

RAMP_RATE_HZ = 100.0
"""Goal updates per second during the stop ramp (well inside any Bus Watchdog period)."""


def safe_pose(robot: RobotConfig) -> np.ndarray:
    """The pose a stop ramps to: every joint straight (0 rad), clipped to its limits; shape (N,)."""
    pose: np.ndarray = np.clip(np.zeros(robot.joint_count), robot.lower_rad, robot.upper_rad)
    return pose


def ramp_duration_s(span_rad: float, max_speed_rad_s: float, duration_s: float) -> float:
    """The stop ramp's length in s: ``duration_s``, stretched so no joint beats the speed limit.

    A cosine ramp over T seconds peaks at (pi / 2) * span / T, so the shortest ramp that keeps
    every joint under ``max_speed_rad_s`` lasts (pi / 2) * span / max_speed (``span_rad`` is the
    largest distance a joint travels).
    """
    return max(duration_s, fastest_ramp_s(span_rad, max_speed_rad_s))


def fastest_ramp_s(span_rad: float, max_speed_rad_s: float) -> float:
    """The shortest cosine ramp over ``span_rad`` whose peak speed stays under the limit (s)."""
    return 0.5 * math.pi * abs(span_rad) / max_speed_rad_s


def ramp_poses(
    start_rad: np.ndarray, target_rad: np.ndarray, duration_s: float, rate_hz: float = RAMP_RATE_HZ
) -> list[tuple[float, np.ndarray]]:
    """(time from start in s, pose in rad) waypoints of a cosine ramp, ending exactly on target.

    The cosine profile starts and ends at zero velocity, so neither end jerks the chain. A zero
    duration gives the target alone.
    """
    steps = max(1, math.ceil(duration_s * rate_hz))
    span = np.asarray(target_rad, dtype=float) - np.asarray(start_rad, dtype=float)
    poses = []
    for k in range(1, steps + 1):
        weight = 0.5 - 0.5 * math.cos(math.pi * k / steps)
        poses.append((duration_s * k / steps, start_rad + weight * span))
    poses[-1] = (duration_s, np.asarray(target_rad, dtype=float).copy())
    return poses
