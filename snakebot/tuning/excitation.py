"""Record a log that identifies the servo well: one joint chirps while the others hold.

Friction against the floor makes a replay depend on tiny differences (stick or slip), which
hides the servo's own parameters; so the recipe is to bend a pitch joint until the modules it
moves are off the ground (``hold_rad``), then chirp it there. On the twin such a log replays to
1e-5 rad and sysid recovers the parameters it was made with (docs/tuning.md).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from snakebot.backends.base import Backend
from snakebot.config.schema import RobotConfig
from snakebot.control.runner import play_commands
from snakebot.control.safety import SafetyLayer, smooth_ramp
from snakebot.errors import ConfigError
from snakebot.telemetry import CsvTelemetryWriter
from snakebot.tuning.responses import chirp_commands
from snakebot.tuning.trace import FloatArray


def chirp_plan(
    robot: RobotConfig,
    start_rad: FloatArray,
    joint: int,
    hold_rad: float,
    *,
    amplitude_rad: float = 0.12,
    duration_s: float = 4.0,
    stop_hz: float = 6.0,
    ramp_s: float = 1.0,
    rate_hz: float = 100.0,
) -> FloatArray:
    """Commands (K, N): ramp ``joint`` to ``hold_rad``, chirp it, ramp back to ``start_rad``."""
    if not 0 <= joint < robot.joint_count:
        raise ConfigError("joint", str(joint), f"expected 0..{robot.joint_count - 1}")
    peak = amplitude_rad * 2 * math.pi * stop_hz
    if peak > robot.max_speed_rad_s:
        raise ConfigError(
            "amplitude_rad",
            f"{amplitude_rad:g}",
            f"the chirp would need {peak:.1f} rad/s at "
            f"{stop_hz:g} Hz, more than the allowed {robot.max_speed_rad_s:.1f} rad/s",
        )
    hold = start_rad.copy()
    hold[joint] = hold_rad
    low, high = robot.lower_rad[joint], robot.upper_rad[joint]
    if not (low <= hold_rad - amplitude_rad and hold_rad + amplitude_rad <= high):
        raise ConfigError("hold_rad", f"{hold_rad:g}", "the chirp would leave the joint's limits")
    steps = max(1, round(ramp_s * rate_hz))
    fraction = np.array([smooth_ramp((k + 1) / steps) for k in range(steps)])[:, None]
    ramp_in = start_rad + fraction * (hold - start_rad)
    chirp = chirp_commands(
        hold, joint, amplitude_rad, rate_hz=rate_hz, duration_s=duration_s, stop_hz=stop_hz
    )
    ramp_out = hold + fraction * (start_rad - hold)
    commands: FloatArray = np.vstack([ramp_in, chirp, ramp_out])
    return commands


def record(
    backend: Backend, robot: RobotConfig, commands: FloatArray, path: Path, rate_hz: float = 100.0
) -> int:
    """Play commands (K, N) on a connected backend through the control loop behind the
    robot's clip-only safety layer, logging every cycle to ``path`` (the CSV of ``snakebot
    run --log``); returns the rows written."""
    with CsvTelemetryWriter(path, backend.joint_count) as log:
        play_commands(backend, commands, rate_hz, SafetyLayer.clip_only(robot), observers=[log])
        return log.rows
