"""What a drive starts from: the default gait list and the live gait for a robot.

Shared by ``snakebot drive`` and scripts that call :func:`snakebot.drive.run.run_drive`; errors
name the parameter (``smoothing_s``), never a command-line flag.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from snakebot.config import RobotConfig
from snakebot.drive.controller import GaitChoice
from snakebot.errors import ConfigError
from snakebot.gaits.live import LiveGait

PLANAR_GAITS = ("serpenoid",)
"""The default keys 1-9 on an all-yaw (planar) robot."""
SPATIAL_GAITS = (
    "sidewinding",
    "rolling",
    "lateral_undulation",
    "turn_in_place",
    "linear_progression",
)
"""The default keys 1-9 on a robot with pitch joints."""
MAX_GAITS = 9
DEFAULT_SMOOTHING_S = 0.5
"""Seconds for a drive control (speed, turn, amplitude) to move one unit."""
DEFAULT_TRANSITION_S = 1.0
"""Shortest blend between two gaits, in s (longer when the servos need it)."""


def default_gaits(robot: RobotConfig) -> tuple[str, ...]:
    """The gaits keys 1-9 select when none are named: planar ones for an all-yaw robot."""
    planar = all(joint.axis == "yaw" for joint in robot.joints)
    return PLANAR_GAITS if planar else SPATIAL_GAITS


def live_gait(
    robot: RobotConfig,
    *,
    rate_hz: float,
    smoothing_s: float = DEFAULT_SMOOTHING_S,
    transition_s: float = DEFAULT_TRANSITION_S,
    gaits: Sequence[GaitChoice] = (),
) -> LiveGait:
    """The live gait for ``robot`` at ``rate_hz``: its limits and speed, steering on the yaw
    joints; ``smoothing_s`` for a control to move one unit, ``transition_s`` the shortest
    blend between gaits. Each of ``gaits`` is checked to be drivable with its parameters.

    Raises ConfigError naming ``smoothing_s``/``transition_s``/``gaits`` for a bad value,
    GaitError for a gait that cannot be driven live.
    """
    for name, value in (("smoothing_s", smoothing_s), ("transition_s", transition_s)):
        if not (value >= 0 and math.isfinite(value)):
            raise ConfigError(name, "", f"expected seconds >= 0, got {value!r}")
    if gaits and len(gaits) > MAX_GAITS:
        raise ConfigError("gaits", "", f"expected 1 to {MAX_GAITS} gaits, got {len(gaits)}")
    live = LiveGait(
        robot.joint_count,
        lower_rad=robot.lower_rad,
        upper_rad=robot.upper_rad,
        max_speed_rad_s=robot.max_speed_rad_s,
        period_s=1.0 / rate_hz,
        steer=[1.0 if joint.axis == "yaw" else 0.0 for joint in robot.joints],
        smoothing_s=smoothing_s,
        transition_s=transition_s,
    )
    for choice in gaits:
        live.check(choice.name, choice.params)
    return live
