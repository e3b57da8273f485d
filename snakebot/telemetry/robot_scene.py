"""The scene geometry of a robot on a backend: the twin's bodies, or FK of measured joints."""

from __future__ import annotations

from typing import Any

from snakebot.backends.base import Backend
from snakebot.config.schema import RobotConfig
from snakebot.telemetry.foxglove_live import Geometry
from snakebot.telemetry.scene import KinematicLinkPoses, LinkPoses, TwinLinkPoses


def robot_geometry(robot: Any, backend: Backend) -> Geometry | None:
    """The scene of ``robot`` on ``backend``: None for robots that are not a servo chain (a
    mass-spring body). The twin's link poses are its simulated bodies'; any other backend's are
    the forward kinematics of its measured joints, built now so the first cycle is not late."""
    if not isinstance(robot, RobotConfig):
        return None
    from snakebot.backends.twin import TwinBackend

    if isinstance(backend, TwinBackend):
        twin = backend

        def twin_poses() -> LinkPoses:
            return TwinLinkPoses(twin.model, twin.data, robot.link_count)

        factory = twin_poses
    else:
        kinematic = KinematicLinkPoses(robot)

        def kinematic_poses() -> LinkPoses:
            return kinematic

        factory = kinematic_poses
    return Geometry(robot.link_count, robot.link.length_m, robot.link.radius_m, factory)
