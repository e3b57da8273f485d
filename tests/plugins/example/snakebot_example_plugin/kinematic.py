"""A kinematic backend: joints that reach every commanded angle at once, or at a top speed.

No physics and no hardware, so it is the simplest backend that passes snakebot's contract
(snakebot.testing.BackendContract): a template for your own, and a quick way to check a gait's
commands. Robot time is simulated: ``advance(dt)`` moves it by exactly ``dt``.
"""

from __future__ import annotations

import numpy as np

from snakebot.backends.base import Backend
from snakebot.backends.registry import BackendOption, BackendSpec
from snakebot.config import RobotConfig
from snakebot.errors import ConfigError
from snakebot.types import JointState, PDGains


class KinematicBackend(Backend):
    """Joints move straight to the goal (or toward it at ``max_speed_rad_s``, in rad/s) while
    torque is on; they stay where they are while it is off."""

    def __init__(self, robot: RobotConfig, *, max_speed_rad_s: float | str | None = None) -> None:
        super().__init__()
        if not isinstance(robot, RobotConfig):
            raise ConfigError(str(getattr(robot, "name", robot)), "", "needs a servo robot file")
        speed = None if max_speed_rad_s is None else float(max_speed_rad_s)
        if speed is not None and not speed > 0:
            raise ConfigError("max_speed_rad_s", "", f"expected rad/s > 0, got {max_speed_rad_s!r}")
        self.robot = robot
        self.joint_count = robot.joint_count
        self.stop_policy = robot.safety.stop_policy
        self.max_speed_rad_s = speed
        self._time_s = 0.0
        self._position = np.zeros(self.joint_count)
        self._velocity = np.zeros(self.joint_count)
        self._goal = np.zeros(self.joint_count)

    def _connect(self) -> None:
        self._position = np.zeros(self.joint_count)  # straight, as a twin starts
        self._goal = self._position.copy()
        self.torque_enabled = True

    def _close(self) -> None:
        self.set_torque(self.stop_policy == "hold")

    def _read_state(self) -> JointState:
        return JointState(
            self._time_s, self._position.copy(), self._velocity.copy(), np.zeros(self.joint_count)
        )

    def _send_command(self, position_rad: np.ndarray) -> None:
        self._goal = position_rad.copy()

    def _set_gains(self, gains: PDGains) -> None:
        pass  # a perfect joint has no loop to tune

    def _set_torque(self, enabled: bool) -> None:
        self.torque_enabled = enabled

    def _advance(self, dt_s: float) -> None:
        before = self._position.copy()
        if self.torque_enabled:
            step = self._goal - self._position
            if self.max_speed_rad_s is not None:
                step = np.clip(step, -self.max_speed_rad_s * dt_s, self.max_speed_rad_s * dt_s)
            self._position = self._position + step
        self._velocity = (self._position - before) / dt_s
        self._time_s += dt_s


SPEC = BackendSpec(
    name="kinematic",
    summary="joints that follow every command at once (no physics, no hardware)",
    factory=KinematicBackend,
    options=(BackendOption("max_speed_rad_s", "top joint speed in rad/s (default: none)"),),
)
