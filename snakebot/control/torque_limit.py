"""A torque cap per run: every servo follows the gait but pushes with no more than a limit.

On servos with current-based position control (Dynamixel Operating Mode 5) the cap is Goal
Current = torque / kt (the torque constant from the servo file); on the rigid twin it is the
actuators' force range (``LimitsTorque`` in ``snakebot.backends.capabilities``). Where the snake
is held (a peg, a wall), a capped joint gives way instead of pushing towards an overload.
"""

from __future__ import annotations

import math

import numpy as np

from snakebot.backends.capabilities import LimitsTorque
from snakebot.config.schema import RobotConfig
from snakebot.errors import ConfigError

__all__ = ["limit_servo_torque"]


def limit_servo_torque(
    backend: object, robot: object, torque_nm: float, where: str = "torque limit"
) -> None:
    """Cap every servo of ``backend`` (of ``robot``) at ``torque_nm`` N*m; call before it
    connects, so the cap holds from the first push. ConfigError naming ``where`` for a value
    that is not finite and > 0, one above the servos' stall torque, or a backend (servo model,
    soft body) that cannot cap its torque."""
    servo = robot.servo if isinstance(robot, RobotConfig) else None
    stall = servo.physics.stall_torque_nm if servo is not None else math.inf
    if not (math.isfinite(torque_nm) and 0 < torque_nm <= stall):
        bound = f" (the {servo.name}'s stall torque)" if servo is not None else ""
        raise ConfigError(where, "", f"expected 0 < N*m <= {stall:.3g}{bound}, got {torque_nm}")
    if not isinstance(robot, RobotConfig) or not isinstance(backend, LimitsTorque):
        what = type(backend).__name__ + (f" with {servo.name} servos" if servo else "")
        raise ConfigError(
            where,
            "",
            f"a torque limit needs current-based position control, and {what} has none: on "
            "servos it needs Operating Mode 5 (XM430, XM540, XH430, XL330, MX-64/106 2.0; not "
            "XL430, AX, MX 1.0 or Feetech), and the rigid twin models it",
        )
    backend.limit_torque(np.full(robot.joint_count, torque_nm))
