"""Goal-task presets: named env and PPO settings that ``rl train --task`` and ``rl compare --task``
start from (``--set`` and ``--ppo`` still override each one).

``near`` is the environment's defaults: goals 2-4 body lengths from the centre of mass, a
small per-step cost, 30 s episodes. ``seed`` is the seed's task as its text states it: goals
5-7 m from the head, -1 per step and +100 at the goal, episodes of 2000 policy steps (200 s at
the default 10 Hz) and PPO's discount 0.999. What the seed leaves unsaid (the velocity and
distance weights, the goal radius, the bearing) stays at the environment's defaults.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from snakebot.errors import ConfigError


@dataclass(frozen=True)
class GoalTask:
    """One preset: ``env`` (GoalSettings / EnvSettings fields) and ``ppo`` (PPO settings)."""

    name: str
    summary: str
    env: dict[str, Any] = field(default_factory=dict)
    ppo: dict[str, Any] = field(default_factory=dict)


GOAL_TASKS: MappingProxyType[str, GoalTask] = MappingProxyType(
    {
        "near": GoalTask("near", "goals 2-4 body lengths from the COM, 30 s episodes"),
        "seed": GoalTask(
            "seed",
            "the seed's task: goals 5-7 m from the head, -1 a step, +100 at the goal, "
            "200 s episodes, gamma 0.999",
            env={
                "goal_distance_m": (5.0, 7.0),
                "goal_from": "head",
                "step_cost": 1.0,
                "goal_bonus": 100.0,
                "episode_s": 200.0,
            },
            ppo={"gamma": 0.999},
        ),
    }
)
"""The presets by name; ``near`` is what every goal run without ``--task`` gets."""


def goal_task(name: str) -> GoalTask:
    """The preset called ``name``; ConfigError naming the task and listing the presets."""
    try:
        return GOAL_TASKS[name]
    except KeyError:
        raise ConfigError(
            "task", name, f"unknown goal task; expected one of {', '.join(GOAL_TASKS)}"
        ) from None


__all__ = ["GOAL_TASKS", "GoalTask", "goal_task"]
