"""Learning to move: Gymnasium environments on the twin, training, and policies as gaits.

The one package of snakebot that imports gymnasium (the ``rl`` extra); stable-baselines3 and
torch (the ``rl-train`` extra) are imported only by training and evaluation. Importing this
package registers ``snakebot/SnakeGoal-v0`` and ``snakebot/SnakeVelocity-v0``::

    import gymnasium, snakebot.rl
    env = gymnasium.make("snakebot/SnakeGoal-v0", encoding="dft_shift")

(or, with no import, ``gymnasium.make("snakebot.rl:snakebot/SnakeGoal-v0")``). Raises
MissingDependencyError naming the extra when gymnasium is not installed.
"""

from __future__ import annotations

from snakebot.rl.deps import require
from snakebot.rl.encodings import ENCODINGS, SEED_ENCODINGS
from snakebot.rl.settings import ENV_IDS, GOAL_ENV_ID, VELOCITY_ENV_ID

gymnasium = require("gymnasium", "snakebot.rl (the learning environments)")


def register_envs() -> None:
    """Register both environments with gymnasium (idempotent); string entry points, so the
    twin is built only when ``gymnasium.make`` is called."""
    registered = gymnasium.envs.registry
    entries = {
        GOAL_ENV_ID: "snakebot.rl.goal_env:SnakeGoalEnv",
        VELOCITY_ENV_ID: "snakebot.rl.velocity_env:SnakeVelocityEnv",
    }
    for env_id, entry_point in entries.items():
        if env_id not in registered:
            gymnasium.register(id=env_id, entry_point=entry_point)


register_envs()

__all__ = [
    "ENCODINGS",
    "ENV_IDS",
    "GOAL_ENV_ID",
    "SEED_ENCODINGS",
    "VELOCITY_ENV_ID",
    "register_envs",
]
