"""Evaluate a policy folder against a zero and a random policy on the same episode seeds.

Goal task: success rate, time to goal (successful episodes), speed (COM path / time) and cost
of transport (positive joint work / (m g path); none when the COM travelled under 1 mm per
episode, three significant figures in the table). Velocity task: the commanded and the achieved
speed and turn rate. Needs only the ``rl`` extra: the saved actor is plain numpy.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from snakebot.control.metrics import GRAVITY_M_S2
from snakebot.gaits.base import FloatArray
from snakebot.rl.policy_file import load_policy
from snakebot.rl.settings import GOAL_ENV_ID

Policy = Callable[[np.ndarray], FloatArray]
MIN_PATH_M = 1e-3  # mean COM path per episode below which a policy did not travel


@dataclass
class EpisodeStats:
    """One episode: return, steps, success, time to goal, path, work, speeds."""

    seed: int
    episode_return: float
    steps: int
    success: bool
    duration_s: float
    path_m: float
    positive_work_j: float
    speed_error_mps: float = math.nan
    command: tuple[float, float] | None = None
    achieved: tuple[float, float] | None = None


@dataclass
class EvalResult:
    """All episodes of one policy."""

    name: str
    mass_kg: float
    episodes: list[EpisodeStats] = field(default_factory=list)

    def summary(self) -> dict[str, Any]:
        """Means over episodes, JSON-ready (None where undefined)."""
        eps = self.episodes
        successes = [e for e in eps if e.success]
        path = sum(e.path_m for e in eps)
        time_s = sum(e.duration_s for e in eps)
        work = sum(e.positive_work_j for e in eps)
        out: dict[str, Any] = {
            "episodes": len(eps),
            "mean_return": _mean([e.episode_return for e in eps]),
            # a velocity task has commands to follow, no goal to reach
            "success_rate": len(successes) / len(eps)
            if eps and all(e.command is None for e in eps)
            else None,
            "successes": len(successes),
            "time_to_goal_s": _mean([e.duration_s for e in successes]),
            "speed_mps": path / time_s if time_s > 0 else None,
            # A snake that stayed put has no cost of transport (work over numerical drift
            # gave 1.6e-21 for a zero policy): defined from MIN_PATH_M per episode on.
            "cost_of_transport": work / (self.mass_kg * GRAVITY_M_S2 * path)
            if eps and path >= MIN_PATH_M * len(eps)
            else None,
        }
        if any(e.command is not None for e in eps):
            out["speed_error_mps"] = _mean([e.speed_error_mps for e in eps])
            out["commands"] = [{"command": e.command, "achieved": e.achieved} for e in eps]
        return out


def _mean(values: list[float]) -> float | None:
    finite = [v for v in values if math.isfinite(v)]
    return float(np.mean(finite)) if finite else None


def run_episodes(
    env: Any, policy: Policy, name: str, seeds: list[int], *, frames: list[np.ndarray] | None = None
) -> EvalResult:
    """Play ``policy`` for one episode per seed; frames of the first go to ``frames``."""
    result = EvalResult(name, float(env.unwrapped.robot.total_mass_kg))
    for index, seed in enumerate(seeds):
        obs, info = env.reset(seed=seed)
        total, steps, work, path = 0.0, 0, 0.0, 0.0
        speeds: list[float] = []
        turns: list[float] = []
        com = np.asarray(env.unwrapped.loop.body().com_m[:2])
        done, success = False, False
        while not done:
            obs, reward, terminated, truncated, info = env.step(policy(obs).astype(np.float32))
            total += reward
            steps += 1
            work += info["positive_work_j"]
            new = info["com_m"][:2]
            path += float(np.linalg.norm(new - com))
            com = new
            success = success or bool(info.get("is_success", False))
            if "speed_mps" in info:
                speeds.append(info["speed_mps"])
                turns.append(info["turn_rate_rad_s"])
            if frames is not None and index == 0:
                frames.append(env.render())
            done = terminated or truncated
        duration = steps / env.unwrapped.settings.action_hz
        stats = EpisodeStats(seed, total, steps, success, duration, path, work)
        if speeds:
            command = info["command"]
            skip = len(speeds) // 5  # the ramp-in and the first strides
            stats.command = (float(command[0]), float(command[1]))
            stats.achieved = (float(np.mean(speeds[skip:])), float(np.mean(turns[skip:])))
            stats.speed_error_mps = abs(stats.achieved[0] - stats.command[0])
        result.episodes.append(stats)
    return result


def evaluate_folder(
    folder: Path, *, episodes: int, seed: int, baselines: bool, video: Path | None
) -> dict[str, EvalResult]:
    """The trained policy (and, with ``baselines``, zero and random actions) on seeds
    ``seed..seed+episodes-1``. Velocity policies hold one command per episode, drawn by seed."""
    import gymnasium

    import snakebot.rl  # noqa: F401  (registers the envs)

    policy_file = load_policy(folder)
    render = "rgb_array" if video is not None else None
    env = gymnasium.make(policy_file.env_id, render_mode=render, **policy_file.env_kwargs)
    if policy_file.env_id != GOAL_ENV_ID:
        # One command per episode: evaluation asks how well a command is followed.
        velocity_env: Any = env.unwrapped
        velocity_env.task = _hold_commands(velocity_env.task)
    seeds = list(range(seed, seed + episodes))
    frames: list[np.ndarray] | None = [] if video is not None else None
    try:
        results = {"policy": run_episodes(env, policy_file.actor, "policy", seeds, frames=frames)}
        if baselines:
            dim = int(np.prod(env.action_space.shape or (1,)))
            rng = np.random.default_rng(seed)
            results["zero"] = run_episodes(env, lambda _obs: np.zeros(dim), "zero", seeds)
            results["random"] = run_episodes(
                env, lambda _obs: rng.uniform(-1.0, 1.0, dim), "random", seeds
            )
    finally:
        env.close()
    if video is not None and frames:
        write_video(video, frames, env.unwrapped.metadata["render_fps"])
    return results


def _hold_commands(task: Any) -> Any:
    import dataclasses

    return dataclasses.replace(task, command_period_s=1e9)


def write_video(path: Path, frames: list[np.ndarray], fps: int) -> None:
    """Encode RGB frames to ``path`` (imageio + ffmpeg, the ``video`` extra); OutputError
    naming it when it cannot be written or does not read back whole (VideoWriter)."""
    from snakebot.backends.twin.video import VideoWriter

    with VideoWriter(path, fps) as writer:
        for frame in frames:
            writer.append(frame)


def print_table(results: dict[str, EvalResult], out: Any = sys.stdout) -> None:
    """One line per policy."""

    def fmt(value: object, spec: str, unit: str = "") -> str:
        if value is None:  # "n/a", right-aligned where the number and its unit would stand
            width = int(spec.split(".")[0] or 0) + len(unit)
            return "n/a".rjust(width)
        return format(value, spec) + unit

    out.write(
        f"{'policy':8s} {'episodes':>8s} {'success':>8s} {'to goal':>9s} {'speed':>10s} "
        f"{'CoT':>7s} {'return':>9s}\n"
    )
    for name, result in results.items():
        s = result.summary()
        rate = None if s["success_rate"] is None else 100 * s["success_rate"]
        out.write(
            f"{name:8s} {s['episodes']:8d} {fmt(rate, '7.0f', '%')} "
            f"{fmt(s['time_to_goal_s'], '7.1f', ' s')} {fmt(s['speed_mps'], '6.3f', ' m/s')} "
            f"{fmt(s['cost_of_transport'], '7.3g')} "
            f"{fmt(s['mean_return'], '9.2f')}\n"
        )
        if "speed_error_mps" in s:
            out.write(f"{'':8s} mean |speed - command| {fmt(s['speed_error_mps'], '.3f')} m/s\n")
