"""Evaluate a policy folder against baseline policies on the same episode seeds and goals.

Baselines: zero and random actions in the policy's own env; on the goal task also two steering
rules on the sinusoid encoding (a serpenoid), the offset turned toward the goal in proportion to
its bearing in the head's frame (offset = -3 x bearing, clipped to the encoding's range):
``bearing`` at mid-range amplitude, frequency and lag (the one-line rule an audit found to
match a 200k-step policy), and ``steered`` at the tuned open-loop serpenoid's amplitude,
frequency and lag (docs/learning.md, "A tuned open-loop gait").

Goal task: success rate, time to goal (successful episodes), speed (COM path / time), path
efficiency (the distance closed toward the goal / the COM path) and cost of transport
(positive joint work, integrated every physics step, / (m g path); none when the COM travelled
under 1 mm per episode, three significant figures in the table). Velocity task: the commanded
and the achieved speed and turn rate. Needs only the ``rl`` extra: the saved actor is plain numpy.
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
from snakebot.errors import ConfigError
from snakebot.gaits.base import FloatArray
from snakebot.rl.intervals import across_seeds, bootstrap_intervals, replace_episodes
from snakebot.rl.policy_file import PolicyFile, load_policy
from snakebot.rl.settings import GOAL_ENV_ID

Policy = Callable[[np.ndarray], FloatArray]
MIN_PATH_M = 1e-3  # mean COM path per episode below which a policy did not travel
BEARING_GAIN = 3.0
"""Serpenoid offset (rad) per rad of goal bearing, against the bearing: the steering rule."""
MID_RANGE_ACTION = (0.0, 0.0, 0.0)
"""Sinusoid-encoding actions for amplitude, frequency and lag: the middle of each range
(0.5 rad, 0.8 Hz, 0.7 rad)."""
TUNED_SERPENOID_ACTION = (-0.2, 1.0, -0.46)
"""The same three for the serpenoid `snakebot tune gait --method grid --budget 25` found on
snake8 (docs/learning.md): 0.4 rad, 1.5 Hz, 0.47 rad."""


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
    progress_m: float = math.nan
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
        """``figures()`` and their 95 % intervals over the episodes (``interval95``: figure ->
        (low, high) or None; ``snakebot.rl.intervals``), JSON-ready."""
        out = self.figures()
        out["interval95"] = bootstrap_intervals(
            self.episodes, lambda picked: replace_episodes(self, picked).figures()
        )
        out["interval_over"] = "episodes"
        return out

    def figures(self) -> dict[str, Any]:
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
            "path_efficiency": _ratio([e.progress_m for e in eps], path, len(eps)),
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


def _ratio(progress_m: list[float], path_m: float, episodes: int) -> float | None:
    """Distance closed toward the goals over the COM path, all episodes together; None
    without goals or a path."""
    closed = [p for p in progress_m if math.isfinite(p)]
    if not closed or path_m < MIN_PATH_M * episodes:
        return None
    return sum(closed) / path_m


def bearing_steering(base_action: tuple[float, float, float], gain: float = BEARING_GAIN) -> Policy:
    """A policy for SnakeGoal-v0's sinusoid encoding: ``base_action`` for amplitude, frequency
    and lag, and the offset ``-gain`` x the goal's bearing (rad, from the observation's last
    two entries: the goal in the head's frame), clipped to the encoding's offset range."""
    from snakebot.rl.encodings import OFFSET_RAD, unlerp

    low, high = OFFSET_RAD
    base = np.asarray(base_action, dtype=np.float64)

    def policy(observation: np.ndarray) -> FloatArray:
        bearing = math.atan2(float(observation[-1]), float(observation[-2]))
        offset = min(max(-gain * bearing, low), high)
        action: FloatArray = np.append(base, unlerp(offset, OFFSET_RAD))
        return action

    return policy


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
        goal = info.get("goal_xy_m")
        total, steps, work, path = 0.0, 0, 0.0, 0.0
        speeds: list[float] = []
        turns: list[float] = []
        com = np.asarray(env.unwrapped.loop.body().com_m[:2])
        start = com
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
        if goal is not None:
            goal = np.asarray(goal, dtype=np.float64)
            stats.progress_m = float(np.linalg.norm(goal - start) - np.linalg.norm(goal - com))
        if speeds:
            command = info["command"]
            skip = len(speeds) // 5  # the ramp-in and the first strides
            stats.command = (float(command[0]), float(command[1]))
            stats.achieved = (float(np.mean(speeds[skip:])), float(np.mean(turns[skip:])))
            stats.speed_error_mps = abs(stats.achieved[0] - stats.command[0])
        result.episodes.append(stats)
    return result


@dataclass
class SeedsResult:
    """The evaluations of several policies of one configuration (training seeds), as one row."""

    name: str
    folders: list[Path]
    results: list[EvalResult]

    def summary(self) -> dict[str, Any]:
        """Each figure's mean over the policies with its Student's t 95 % interval over them
        (``snakebot.rl.intervals.across_seeds``), and ``policies``: each one's own summary."""
        out = across_seeds([r.figures() for r in self.results])
        out["policies"] = [
            {"folder": str(folder), **result.summary()}
            for folder, result in zip(self.folders, self.results, strict=True)
        ]
        return out


def load_policies(folders: list[Path]) -> list[PolicyFile]:
    """Policy folders of one configuration (the same env and settings: training seeds);
    ConfigError naming the folder and the first setting that differs from the first one's."""
    policies = [load_policy(folder) for folder in folders]
    first = policies[0]
    for other in policies[1:]:
        keys = sorted(set(first.env_kwargs) | set(other.env_kwargs))
        differ = [k for k in keys if first.env_kwargs.get(k) != other.env_kwargs.get(k)]
        if other.env_id != first.env_id:
            differ = ["env_id"]
        if differ:
            key = differ[0]
            mine = other.env_id if key == "env_id" else other.env_kwargs.get(key)
            theirs = first.env_id if key == "env_id" else first.env_kwargs.get(key)
            raise ConfigError(
                other.folder / "policy.json",
                key if key == "env_id" else f"env_kwargs.{key}",
                f"is {mine!r} where {first.folder} has {theirs!r}: several folders are "
                "evaluated together only as training seeds of one configuration",
            )
    return policies


def evaluate_folder(
    folder: Path | list[Path], *, episodes: int, seed: int, baselines: bool, video: Path | None
) -> dict[str, EvalResult | SeedsResult]:
    """The trained policy (and, with ``baselines``, zero and random actions, and on the goal
    task the ``bearing`` and ``steered`` serpenoids) on seeds ``seed..seed+episodes-1``: the
    same start and goal per seed for every policy. Velocity policies hold one command per
    episode, drawn by seed. Several folders (``load_policies``: training seeds of one
    configuration) make the ``policy`` row a SeedsResult; the video shows the first one's."""
    import gymnasium

    import snakebot.rl  # noqa: F401  (registers the envs)

    policies = load_policies(folder if isinstance(folder, list) else [folder])
    policy_file = policies[0]
    env = make_eval_env(policy_file, render=video is not None)
    seeds = list(range(seed, seed + episodes))
    frames: list[np.ndarray] | None = [] if video is not None else None
    try:
        played = [
            run_episodes(env, p.actor, "policy", seeds, frames=frames if i == 0 else None)
            for i, p in enumerate(policies)
        ]
        results: dict[str, EvalResult | SeedsResult] = {
            "policy": played[0]
            if len(played) == 1
            else SeedsResult("policy", [p.folder for p in policies], played)
        }
        if baselines:
            dim = int(np.prod(env.action_space.shape or (1,)))
            rng = np.random.default_rng(seed)
            results["zero"] = run_episodes(env, lambda _obs: np.zeros(dim), "zero", seeds)
            results["random"] = run_episodes(
                env, lambda _obs: rng.uniform(-1.0, 1.0, dim), "random", seeds
            )
            if policy_file.env_id == GOAL_ENV_ID:
                kwargs = {**policy_file.env_kwargs, "encoding": "sinusoid"}
                steering_env = gymnasium.make(GOAL_ENV_ID, **kwargs)
                try:
                    for name, base in (
                        ("bearing", MID_RANGE_ACTION),
                        ("steered", TUNED_SERPENOID_ACTION),
                    ):
                        results[name] = run_episodes(
                            steering_env, bearing_steering(base), name, seeds
                        )
                finally:
                    steering_env.close()
    finally:
        env.close()
    if video is not None and frames:
        write_video(video, frames, env.unwrapped.metadata["render_fps"])
    return results


def make_eval_env(policy_file: PolicyFile, *, render: bool = False) -> Any:
    """The policy's env as evaluation plays it: its saved settings, and on the velocity task
    one command held per episode (evaluation asks how well a command is followed)."""
    import gymnasium

    import snakebot.rl  # noqa: F401  (registers the envs)

    mode = "rgb_array" if render else None
    env = gymnasium.make(policy_file.env_id, render_mode=mode, **policy_file.env_kwargs)
    if policy_file.env_id != GOAL_ENV_ID:
        velocity_env: Any = env.unwrapped
        velocity_env.task = _hold_commands(velocity_env.task)
    return env


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


def print_table(results: dict[str, EvalResult | SeedsResult], out: Any = sys.stdout) -> None:
    """One line per policy, then each one's 95 % intervals (``snakebot.rl.intervals``)."""

    def fmt(value: object, spec: str, unit: str = "") -> str:
        if value is None:  # "n/a", right-aligned where the number and its unit would stand
            width = int(spec.split(".")[0] or 0) + len(unit)
            return "n/a".rjust(width)
        return format(value, spec) + unit

    summaries = {name: result.summary() for name, result in results.items()}
    out.write(
        f"{'policy':8s} {'episodes':>8s} {'success':>8s} {'to goal':>9s} {'speed':>10s} "
        f"{'path eff':>8s} {'CoT':>7s} {'return':>9s}\n"
    )
    for name, s in summaries.items():
        rate = None if s["success_rate"] is None else 100 * s["success_rate"]
        out.write(
            f"{name:8s} {s['episodes']:8d} {fmt(rate, '7.0f', '%')} "
            f"{fmt(s['time_to_goal_s'], '7.1f', ' s')} {fmt(s['speed_mps'], '6.3f', ' m/s')} "
            f"{fmt(s['path_efficiency'], '8.2f')} {fmt(s['cost_of_transport'], '7.3g')} "
            f"{fmt(s['mean_return'], '9.2f')}\n"
        )
        if "speed_error_mps" in s:
            out.write(f"{'':8s} mean |speed - command| {fmt(s['speed_error_mps'], '.3f')} m/s\n")
    seeds = [s["training_seeds"] for s in summaries.values() if "training_seeds" in s]
    over = (
        f"the policy over {seeds[0]} training seeds, the rest bootstrap over episodes"
        if seeds
        else "bootstrap over episodes"
    )
    out.write(f"95% intervals ({over})\n")
    columns = (
        ("success %", "success_rate", ".0f", 100.0),
        ("to goal s", "time_to_goal_s", ".1f", 1.0),
        ("speed m/s", "speed_mps", ".3f", 1.0),
        ("path eff", "path_efficiency", ".2f", 1.0),
        ("CoT", "cost_of_transport", ".3g", 1.0),
        ("return", "mean_return", ".2f", 1.0),
    )
    out.write(f"{'policy':8s}" + "".join(f" {title:>16s}" for title, *_ in columns) + "\n")
    for name, s in summaries.items():
        cells = []
        for _, key, spec, scale in columns:
            interval = s["interval95"].get(key)
            cell = (
                "n/a"
                if interval is None
                else f"[{format(interval[0] * scale, spec)}, {format(interval[1] * scale, spec)}]"
            )
            cells.append(f" {cell:>16s}")
        out.write(f"{name:8s}" + "".join(cells) + "\n")
