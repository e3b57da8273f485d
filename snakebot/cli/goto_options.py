"""``snakebot run --to X,Y``: the gait steered to a point by the odometry, kept out of run_cmd."""

from __future__ import annotations

import math

from snakebot.config import RobotConfig
from snakebot.config.body import BodyConfig
from snakebot.errors import ConfigError, UsageError
from snakebot.estimation import ChainGeometry, ChassisOdometry, OdometryConfig
from snakebot.estimation.goto import STEERABLE_GAITS, GoToPoint, SteeringConfig
from snakebot.gaits import Gait


def parse_point(text: str) -> tuple[float, float]:
    """``X,Y`` as two finite numbers (m); ConfigError naming --to otherwise."""
    try:
        x, y = (float(part) for part in text.split(","))
    except ValueError:
        raise ConfigError("--to", text, "expected a point X,Y in m, e.g. 1.5,0.5") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ConfigError("--to", text, "expected two finite numbers X,Y")
    return x, y


def steered_gait(
    robot: RobotConfig | BodyConfig, gait_name: str, gait: Gait, point: str
) -> tuple[str, Gait, GoToPoint]:
    """The --to gait: ``gait`` steered to ``point`` by the odometry of the measured joints
    (the odometry is the returned GoToPoint's, for the run's observers). UsageError for a
    mass-spring body or a gait that is not steered this way."""
    if isinstance(robot, BodyConfig):
        raise UsageError(f"--to steers servo snakes (robot files); {robot.name} is a body file")
    if gait_name not in STEERABLE_GAITS:
        raise UsageError(
            f"--to steers {', '.join(STEERABLE_GAITS)} (travel along the body, a yaw offset "
            f"turns it); not {gait_name}"
        )
    odometry = odometry_for(robot)
    yaw_mask = [joint.axis == "yaw" for joint in robot.joints]
    # It stops early by the way the ramp-out still goes: about half its length at full speed.
    config = SteeringConfig(coast_s=0.5 * robot.safety.ramp_s)
    steering = GoToPoint(gait, odometry, parse_point(point), yaw_mask, config)
    return f"{gait_name}:to", steering, steering


def odometry_for(robot: RobotConfig | BodyConfig) -> ChassisOdometry:
    """The odometry of ``robot``'s chain with the default settings (docs/estimation.md);
    UsageError for a mass-spring body (no joints to measure)."""
    if isinstance(robot, BodyConfig):
        raise UsageError(f"the odometry reads servo joints; {robot.name} is a body file")
    return ChassisOdometry(
        ChainGeometry.of_robot(robot), OdometryConfig(radius_m=robot.link.radius_m)
    )


def steering_summary(steering: GoToPoint) -> dict[str, object]:
    """What a --to run adds to the summary: the point in the estimate's world, the estimated
    distance to it at the end and whether that is within the tolerance."""
    goal = steering.goal_m
    distance = steering.distance_m()
    return {
        "to_point_m": list(steering.point_m),
        "goal_m": None if goal is None else [float(v) for v in goal],
        "estimated_distance_to_goal_m": distance,
        "reached": distance is not None and distance <= steering.config.tolerance_m,
    }
