"""``snakebot/SnakeGoal-v0``: reach a random goal (the task of "Serpentile Locomotion").

Reward per step, each term in ``info["reward_terms"]``: ``step`` (-step_cost), ``velocity``
(+velocity_weight * COM velocity *toward* the goal in body lengths/s: the seed paid for moving
away), ``distance`` (-distance_weight * distance in body lengths) and ``goal`` (+goal_bonus when
the COM comes within goal_radius_bl, which terminates the episode).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from snakebot.gaits.base import FloatArray
from snakebot.rl.base_env import SnakeEnv
from snakebot.rl.episode import StepOutcome
from snakebot.rl.observe import goal_observation
from snakebot.rl.settings import GoalSettings, split_kwargs


class SnakeGoalEnv(SnakeEnv):
    """Reach a goal drawn at reset. kwargs: any field of EnvSettings and GoalSettings.

    Observation (float32): joint angles / limit (N), joint velocities / speed limit (N),
    (sin, cos) of the gait phases (2P, P >= 1), the goal from the COM in the head's frame in
    body lengths (2). ``reset(options={"goal_xy_m": (x, y)})`` sets the goal instead of drawing it.
    """

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        settings, goal = split_kwargs(kwargs, GoalSettings)
        self.goal_settings: GoalSettings = goal
        self.goal_xy_m = np.zeros(2)
        self._last_distance_bl = 0.0
        super().__init__(settings, render_mode)

    def observation_size(self) -> int:
        """2N + 2P + 2."""
        return 2 * self.robot.joint_count + 2 * self.loop.encoding.observed_phases + 2

    def _obs(self) -> np.ndarray:
        return goal_observation(
            self.loop.state,
            self.loop.body(),
            self.goal_xy_m,
            self.phases,
            self.limits,
            self.max_speed_rad_s,
            self.loop.body_length_m,
        )

    def _task_reset(self, options: dict[str, Any]) -> dict[str, Any]:
        com = self.loop.body().com_m[:2]
        if "goal_xy_m" in options:
            self.goal_xy_m = np.asarray(options["goal_xy_m"], dtype=np.float64).reshape(2)
        else:
            g = self.goal_settings
            if g.goal_distance_m is None:
                distance = self.np_random.uniform(*g.goal_distance_bl) * self.loop.body_length_m
            else:
                distance = self.np_random.uniform(*g.goal_distance_m)
            bearing = self.np_random.uniform(*g.goal_bearing_rad)
            origin = com if g.goal_from == "com" else self.loop.head_xy_m()
            self.goal_xy_m = origin + distance * np.array([math.cos(bearing), math.sin(bearing)])
        self._last_distance_bl = self._distance_bl(com)
        return {"goal_xy_m": self.goal_xy_m.copy(), "distance_bl": self._last_distance_bl}

    def _distance_bl(self, com_xy: FloatArray) -> float:
        return float(np.linalg.norm(self.goal_xy_m - com_xy)) / self.loop.body_length_m

    def _task_step(self, outcome: StepOutcome) -> tuple[float, bool, dict[str, Any]]:
        g, length = self.goal_settings, self.loop.body_length_m
        before, after = outcome.com_before_m[:2], outcome.com_after_m[:2]
        to_goal = self.goal_xy_m - before
        direction = to_goal / max(float(np.linalg.norm(to_goal)), 1e-9)
        speed_bl_s = float((after - before) @ direction) * self.settings.action_hz / length
        distance_bl = self._distance_bl(after)
        reached = distance_bl <= g.goal_radius_bl
        terms = {
            "step": -g.step_cost,
            "velocity": g.velocity_weight * speed_bl_s,
            "distance": -g.distance_weight * distance_bl,
            "goal": g.goal_bonus if reached else 0.0,
        }
        info = {
            "reward_terms": terms,
            "distance_bl": distance_bl,
            "speed_to_goal_bl_s": speed_bl_s,
            "is_success": reached,
            "positive_work_j": outcome.positive_work_j,
            "com_m": outcome.com_after_m.copy(),
        }
        return sum(terms.values()), reached, info
