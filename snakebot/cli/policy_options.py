"""``snakebot run --policy DIR --command A,B``: the checks and the gait, kept out of run_cmd.

The policy modules import gymnasium, so they are imported only when ``--policy`` is given.
"""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING

from snakebot.backends.base import Backend
from snakebot.cli.backend_options import flag_errors
from snakebot.config import RobotConfig
from snakebot.config.body import BodyConfig
from snakebot.errors import ConfigError, UsageError
from snakebot.gaits import Gait

if TYPE_CHECKING:
    from snakebot.rl.policy_gait import PoseSource


def parse_command(text: str | None) -> tuple[float, float] | None:
    """``A,B`` as two finite numbers; ConfigError naming --command otherwise."""
    if text is None:
        return None
    parts = text.split(",")
    try:
        a, b = (float(p) for p in parts)
    except ValueError:
        raise ConfigError("--command", text, "expected two numbers A,B, e.g. 0.1,0") from None
    if not (math.isfinite(a) and math.isfinite(b)):
        raise ConfigError("--command", text, "expected two finite numbers")
    return a, b


def policy_gait(
    robot: RobotConfig | BodyConfig,
    backend: Backend,
    args: argparse.Namespace,
    *,
    pose: PoseSource | None = None,
) -> tuple[str, Gait]:
    """The --policy gait for ``backend`` (made, not yet connected), a goal policy's pose from
    ``pose`` where given (--odometry); UsageError when --gait, --gait-file or --set come too, or
    the robot is a mass-spring body (no servos to drive)."""
    if args.gait or args.gait_file or args.set:
        raise UsageError("--policy is the gait: drop --gait, --gait-file and --set")
    if isinstance(robot, BodyConfig):
        raise UsageError(
            f"--policy drives servo snakes (robot files); {robot.name} is a mass-spring body"
        )
    from snakebot.rl.policy_gait import policy_gait_for_backend

    with flag_errors({"command": "--command"}):  # --command's destination is policy_command
        return policy_gait_for_backend(
            args.policy, robot, backend, parse_command(args.policy_command), args.rate, pose=pose
        )
