"""Play a gait on the twin as ``snakebot run`` does (safety layer, ramps), for terrain tests."""

from __future__ import annotations

from typing import Any

from snakebot.backends.twin import TwinBackend
from snakebot.config import RobotConfig
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, RunResult, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait


def play(
    twin: TwinBackend,
    robot: RobotConfig,
    gait: str,
    duration_s: float,
    params: dict[str, Any] | None = None,
) -> RunResult:
    """Connect if needed, run ``gait`` for ``duration_s`` at 100 Hz; the runner's result."""
    made = make_gait(
        gait, robot.joint_count, params or {}, lower_rad=robot.lower_rad, upper_rad=robot.upper_rad
    )
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    if not twin.connected:
        twin.connect()
    return run_gait(twin, made, SafetyLayer.for_robot(robot), RunPlan(duration_s), metrics)
