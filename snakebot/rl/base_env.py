"""What both snake environments share: the twin loop, spaces, seeding and rendering."""

from __future__ import annotations

import math
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from snakebot.gaits.base import FloatArray
from snakebot.rl.episode import TwinEpisode
from snakebot.rl.observe import OBS_BOUND
from snakebot.rl.settings import EnvSettings

RENDER_SIZE = (480, 640)  # height, width in pixels


class SnakeEnv(gymnasium.Env[np.ndarray, np.ndarray]):
    """A ``gymnasium.Env`` around the twin loop. Subclasses add the task: ``_obs`` and
    ``_task_step``/``_task_reset``; ``observation_size`` gives the observation's length."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012 (gymnasium's)

    def __init__(self, settings: EnvSettings, render_mode: str | None = None) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']} or "
                f"None, got {render_mode!r}"
            )
        self.settings = settings
        self.render_mode = render_mode
        self.loop = TwinEpisode(settings)
        robot = self.loop.robot
        self.robot = robot
        self.limits = (robot.lower_rad, robot.upper_rad)
        self.max_speed_rad_s = float(robot.max_speed_rad_s)
        self.metadata = {**self.metadata, "render_fps": max(1, round(settings.action_hz))}
        dim = self.loop.encoding.action_dim
        self.action_space = spaces.Box(-1.0, 1.0, shape=(dim,), dtype=np.float32)
        self.observation_space = spaces.Box(
            -OBS_BOUND, OBS_BOUND, shape=(self.observation_size(),), dtype=np.float32
        )
        self.steps = 0
        self._renderer: Any = None

    def observation_size(self) -> int:
        """Length of the observation vector."""
        raise NotImplementedError

    @property
    def phases(self) -> FloatArray:
        """(sin, cos) of the observed gait phases."""
        return self.loop.clock.observed()

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Straight snake at rest at the origin; the task draws its goal or command."""
        super().reset(seed=seed)
        self.steps = 0
        self.loop.reset(float(self.np_random.uniform(0.0, 2 * math.pi)))
        info = self._task_reset(options or {})
        return self._obs(), info

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """One policy period of the gait ``action`` encodes."""
        outcome = self.loop.step(np.asarray(action, dtype=np.float64))
        self.steps += 1
        reward, terminated, info = self._task_step(outcome)
        truncated = not terminated and self.steps >= self.settings.max_steps
        if outcome.physics_health_error is not None:
            # The twin left what a real snake can do: end the episode as a time limit would
            # (truncated, neither a failure nor a goal to the learner), saying why.
            info["physics_health_error"] = outcome.physics_health_error
            truncated = not terminated
        return self._obs(), float(reward), bool(terminated), bool(truncated), info

    def render(self) -> np.ndarray | None:
        """An RGB frame (H, W, 3) uint8 from the tracking camera, when render_mode is set."""
        if self.render_mode != "rgb_array":
            return None
        import mujoco

        if self._renderer is None:
            height, width = RENDER_SIZE
            self._renderer = mujoco.Renderer(self.loop.backend.model, height, width)
        self._renderer.update_scene(self.loop.backend.data, camera="track")
        frame: np.ndarray = self._renderer.render()
        return frame

    def close(self) -> None:
        """Release the renderer and the twin (safe to call twice)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        self.loop.close()

    # -- the task ------------------------------------------------------------------------------
    def _obs(self) -> np.ndarray:
        raise NotImplementedError

    def _task_reset(self, options: dict[str, Any]) -> dict[str, Any]:
        raise NotImplementedError

    def _task_step(self, outcome: Any) -> tuple[float, bool, dict[str, Any]]:
        raise NotImplementedError
