"""``snakebot rl curve``: learning curves from deterministic evaluations of saved checkpoints.

Training's own curve (learning_curve.csv) averages the episodes its *stochastic* rollouts
happened to end: exploration noise included, different episodes at every point. This one
plays every actor snapshot training kept (``checkpoints/actor-STEPS.npz``, ``rl train
--checkpoints``) and the final actor deterministically on the same episode seeds and goals, as
``rl eval`` does, and writes ``eval_curve.csv`` and ``eval_curve.png`` into the policy folder.
Several folders of one configuration (training seeds) also give each point's mean over them
with Student's t 95 % interval (``snakebot.rl.intervals``).
"""

from __future__ import annotations

import csv
import math
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

from snakebot.errors import ConfigError, OutputError
from snakebot.rl.evaluate import load_policies, make_eval_env, run_episodes
from snakebot.rl.intervals import INTERVAL_FIGURES, seed_interval
from snakebot.rl.policy_file import CHECKPOINT_DIR, checkpoint_steps, load_actor

EVAL_CURVE_FILE = "eval_curve.csv"
EVAL_CURVE_PLOT = "eval_curve.png"
EVAL_CURVE_FIELDS = ("steps", "episodes", "first_seed", *INTERVAL_FIGURES)


@dataclass(frozen=True)
class EvalPoint:
    """One checkpoint's deterministic evaluation: env steps trained, and the figures of
    ``EvalResult.figures`` (NaN where undefined: no goal reached, so no time to goal)."""

    steps: int
    episodes: int
    first_seed: int
    success_rate: float
    time_to_goal_s: float
    speed_mps: float
    path_efficiency: float
    cost_of_transport: float
    mean_return: float


def checkpoints(folder: Path) -> list[tuple[int, Path]]:
    """The folder's actor snapshots, (steps, path) by steps; ConfigError naming the folder
    when it has none (trained with --checkpoints 0, or before checkpoints existed)."""
    found = sorted(
        (steps, path)
        for path in (folder / CHECKPOINT_DIR).glob("actor-*.npz")
        if (steps := checkpoint_steps(path)) is not None
    )
    if not found:
        raise ConfigError(
            folder / CHECKPOINT_DIR,
            "",
            "holds no actor snapshots (actor-STEPS.npz): the policy was trained with "
            "checkpoints 0 or before snapshots were kept; train it again (10 are kept by default)",
        )
    return found


def evaluate_checkpoints(
    folder: Path, *, episodes: int, seed: int, progress: TextIO | None = sys.stderr
) -> list[EvalPoint]:
    """Every snapshot of ``folder`` played deterministically on seeds ``seed..seed+episodes-1``
    (the same starts and goals for each). Raises ConfigError for a folder without snapshots
    or with a damaged one (named)."""
    policy_file = load_policies([folder])[0]
    env = make_eval_env(policy_file)
    seeds = list(range(seed, seed + episodes))
    points = []
    try:
        for steps, path in checkpoints(folder):
            figures = run_episodes(env, load_actor(path), "policy", seeds).figures()
            points.append(
                EvalPoint(
                    steps,
                    episodes,
                    seed,
                    **{key: _nan(figures[key]) for key in INTERVAL_FIGURES},
                )
            )
            if progress is not None:
                progress.write(f"  {folder}: {steps} steps: {_line(points[-1])}\n")
                progress.flush()
    finally:
        env.close()
    return points


def write_curve(folder: Path, points: list[EvalPoint]) -> Path:
    """eval_curve.csv and eval_curve.png into ``folder``; OutputError naming what cannot be
    written."""
    from snakebot.rl.plots import curve_plot

    path = folder / EVAL_CURVE_FILE
    try:
        with path.open("w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(EVAL_CURVE_FIELDS)
            for point in points:
                writer.writerow([getattr(point, key) for key in EVAL_CURVE_FIELDS])
    except OSError as exc:
        raise OutputError(path, f"cannot write the curve: {exc.strerror or exc}") from exc
    curve_plot(
        {"deterministic, same goals": points},
        folder / EVAL_CURVE_PLOT,
        title=f"{folder.name}: saved checkpoints, {points[0].episodes} episodes each",
    )
    return path


def across_seeds(curves: dict[Path, list[EvalPoint]]) -> list[dict[str, Any]]:
    """Each checkpoint step's figures averaged over the folders (training seeds) with their
    Student's t 95 % interval; only steps every folder has a snapshot at."""
    common = set.intersection(*({p.steps for p in points} for points in curves.values()))
    rows = []
    for steps in sorted(common):
        at = [next(p for p in points if p.steps == steps) for points in curves.values()]
        row: dict[str, Any] = {"steps": steps, "training_seeds": len(at)}
        for key in INTERVAL_FIGURES:
            values = [getattr(p, key) for p in at if math.isfinite(getattr(p, key))]
            row[key] = sum(values) / len(values) if values else None
            row[f"{key}_interval95"] = seed_interval(values)
        rows.append(row)
    return rows


def print_curve(rows: list[dict[str, Any]], out: TextIO = sys.stdout) -> None:
    """One line per checkpoint step: success, time to goal and return, mean [95 % interval]."""

    def cell(row: dict[str, Any], key: str, spec: str, scale: float = 1.0) -> str:
        value, interval = row[key], row[f"{key}_interval95"]
        if value is None:
            return "n/a"
        text = format(value * scale, spec)
        if interval is not None:
            low, high = (format(v * scale, spec) for v in interval)
            text += f" [{low}, {high}]"
        return text

    seeds = rows[0]["training_seeds"] if rows else 0
    out.write(f"deterministic evaluation of the checkpoints, mean over {seeds} training seed(s)\n")
    out.write(f"{'steps':>9s}  {'success %':>18s}  {'to goal s':>20s}  {'return':>26s}\n")
    for row in rows:
        out.write(
            f"{row['steps']:9d}  {cell(row, 'success_rate', '.0f', 100.0):>18s}  "
            f"{cell(row, 'time_to_goal_s', '.1f'):>20s}  {cell(row, 'mean_return', '.1f'):>26s}\n"
        )


def _nan(value: float | None) -> float:
    return math.nan if value is None else float(value)


def _line(point: EvalPoint) -> str:
    rate = "n/a" if math.isnan(point.success_rate) else f"{100 * point.success_rate:.0f}%"
    return f"success {rate}, return {point.mean_return:.2f}"


__all__ = [
    "EVAL_CURVE_FIELDS",
    "EVAL_CURVE_FILE",
    "EVAL_CURVE_PLOT",
    "EvalPoint",
    "across_seeds",
    "checkpoints",
    "evaluate_checkpoints",
    "print_curve",
    "write_curve",
]
