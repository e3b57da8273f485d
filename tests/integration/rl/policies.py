"""Policy folders made by hand (no training): a numpy actor with chosen weights."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from snakebot.rl.policy_file import NumpyActor, save_actor, write_settings
from snakebot.rl.settings import GoalSettings, VelocitySettings, settings_dict, split_kwargs


def constant_policy(
    folder: Path, env_id: str, action: list[float], obs_dim: int, **kwargs: Any
) -> Path:
    """A policy that always answers ``action`` (zero weights, the action as bias; a tanh
    hidden layer so the folder has the shape SB3's MlpPolicy exports)."""
    task = GoalSettings if "Goal" in env_id else VelocitySettings
    full = settings_dict(*split_kwargs(dict(kwargs), task))
    folder.mkdir(parents=True, exist_ok=True)
    hidden = 4
    actor = NumpyActor(
        (np.zeros((hidden, obs_dim)), np.zeros((len(action), hidden))),
        (np.zeros(hidden), np.asarray(action, dtype=np.float64)),
    )
    save_actor(actor, folder / "actor.npz")
    write_settings(folder, env_id, full, {"algo": "hand-made"})
    return folder


def random_policy(
    folder: Path, env_id: str, action_dim: int, obs_dim: int, seed: int, **kwargs: Any
) -> Path:
    """A policy with random weights: its actions depend on what it observes."""
    task = GoalSettings if "Goal" in env_id else VelocitySettings
    full = settings_dict(*split_kwargs(dict(kwargs), task))
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    actor = NumpyActor(
        (rng.normal(0, 0.5, (16, obs_dim)), rng.normal(0, 0.5, (action_dim, 16))),
        (rng.normal(0, 0.3, 16), rng.normal(0, 0.3, action_dim)),
    )
    save_actor(actor, folder / "actor.npz")
    write_settings(folder, env_id, full, {"algo": "random weights"})
    return folder
