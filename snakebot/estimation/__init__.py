"""State estimation from what the servos report: the virtual chassis and odometry.

- ``ChainGeometry`` (kinematics): forward kinematics of the measured joint angles, numpy only.
- ``VirtualChassis`` (chassis): the body frame of the modules' principal axes (Rollinson, Buchan
  & Choset 2012), its signs and order kept from cycle to cycle.
- ``ChassisOdometry`` (odometry): the chassis's world motion from the modules that touch the
  ground, fused with the head gyro where there is one; a cycle observer and a ``PoseSource``.

Only numpy is imported (no MuJoCo, no SDK): the estimate runs on the servo bus as on the twin.
docs/estimation.md describes the method and its accuracy on the twin.
"""

from snakebot.estimation.chassis import ChassisFrame, VirtualChassis
from snakebot.estimation.kinematics import ChainGeometry
from snakebot.estimation.odometry import ChassisOdometry, OdometryConfig, PlanarPose

__all__ = [
    "ChainGeometry",
    "ChassisFrame",
    "ChassisOdometry",
    "OdometryConfig",
    "PlanarPose",
    "VirtualChassis",
]
