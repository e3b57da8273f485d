"""``snakebot/SnakeVelocity-v0``: follow a commanded forward speed and turn rate.

The policy sees only what the servos report (joint angles, velocities, efforts), the gait
phases and the command, so it can run on a real snake with no external tracking. The command
(speed m/s along the body's heading, turn rate rad/s) is drawn at reset and again every
``command_period_s``. Speeds are measured over one policy step from the COM and the heading
(tail -> head), which only the twin knows: they enter the reward, never the observation.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from snakebot.rl.base_env import SnakeEnv
from snakebot.rl.episode import StepOutcome
from snakebot.rl.observe import velocity_observation
from snakebot.rl.settings import VelocitySettings, split_kwargs


class SnakeVelocityEnv(SnakeEnv):
    """Follow (speed, turn rate) commands. kwargs: any field of EnvSettings, VelocitySettings.

    Observation (float32): joint angles / limit (N), velocities / speed limit (N), efforts /
    stall torque (N), (sin, cos) of the gait phases (2P), the command divided by the largest
    magnitudes of its ranges (2). ``reset(options={"command": (speed_mps, turn_rad_s)})`` holds
    that command for the whole episode.
    """

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        settings, task = split_kwargs(kwargs, VelocitySettings)
        self.task: VelocitySettings = task
        self.command = np.zeros(2)
        self.command_scale = np.array(
            [
                max(abs(v) for v in task.speed_range_mps) or 1.0,
                max(abs(v) for v in task.turn_range_rad_s) or 1.0,
            ]
        )
        self._fixed: np.ndarray | None = None
        self._heading = 0.0
        super().__init__(settings, render_mode)

    def observation_size(self) -> int:
        """3N + 2P + 2."""
        return 3 * self.robot.joint_count + 2 * self.loop.encoding.observed_phases + 2

    def _obs(self) -> np.ndarray:
        return velocity_observation(
            self.loop.state,
            self.phases,
            self.command,
            self.limits,
            self.max_speed_rad_s,
            self.robot.servo.physics.stall_torque_nm,
            self.command_scale,
        )

    def _draw_command(self) -> None:
        if self._fixed is not None:
            self.command = self._fixed.copy()
            return
        self.command = np.array(
            [
                self.np_random.uniform(*self.task.speed_range_mps),
                self.np_random.uniform(*self.task.turn_range_rad_s),
            ]
        )

    def _task_reset(self, options: dict[str, Any]) -> dict[str, Any]:
        fixed = options.get("command")
        self._fixed = None if fixed is None else np.asarray(fixed, dtype=np.float64).reshape(2)
        self._draw_command()
        self._heading = self.loop.heading_rad()
        return {"command": self.command.copy()}

    def _task_step(self, outcome: StepOutcome) -> tuple[float, bool, dict[str, Any]]:
        t = self.task
        rate = self.settings.action_hz
        heading = self.loop.heading_rad()
        turn = math.remainder(heading - self._heading, 2 * math.pi) * rate
        mid = self._heading + 0.5 * math.remainder(heading - self._heading, 2 * math.pi)
        self._heading = heading
        moved = outcome.com_after_m[:2] - outcome.com_before_m[:2]
        speed = float(moved @ np.array([math.cos(mid), math.sin(mid)])) * rate
        effort = outcome.state.effort_nm / self.robot.servo.physics.stall_torque_nm
        command = self.command.copy()
        terms = {
            "speed": math.exp(-(((speed - command[0]) / t.speed_sigma_mps) ** 2)),
            "turn": t.turn_weight * math.exp(-(((turn - command[1]) / t.turn_sigma_rad_s) ** 2)),
            "effort": -t.effort_weight * float(np.mean(effort**2)),
        }
        period = max(1, round(t.command_period_s * rate))
        if self.steps % period == 0:
            self._draw_command()
        info = {
            "reward_terms": terms,
            "command": command,
            "speed_mps": speed,
            "turn_rate_rad_s": turn,
            "positive_work_j": outcome.positive_work_j,
            "com_m": outcome.com_after_m.copy(),
        }
        return sum(terms.values()), False, info
