"""95 % intervals for ``rl eval``'s figures: over training seeds, or over episodes.

Several policy folders of one configuration (``rl compare --seeds N`` writes them) are N draws of
what training produces: each figure's interval is Student's t over the N per-policy figures
(mean +- t(0.975, N-1) x sd / sqrt(N)). A single policy, and every baseline (which does not
train), gets a percentile bootstrap over its episodes instead: the episodes resampled with
replacement ``resamples`` times from a fixed generator, each resample summarised as the whole
run is, resamples where the figure is undefined (no success, so no time to goal) left out.
The two answer different questions: the first how much another training run would differ, the
second how much another set of goals would.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

INTERVAL_FIGURES = (
    "success_rate",
    "time_to_goal_s",
    "speed_mps",
    "path_efficiency",
    "cost_of_transport",
    "mean_return",
)
"""The figures of an evaluation summary that get an interval."""
RESAMPLES = 2000


def seed_interval(values: Sequence[float | None]) -> tuple[float, float] | None:
    """Student's t 95 % interval of the mean of ``values`` (None entries left out); None with
    fewer than two values."""
    from scipy import stats

    finite = np.array([v for v in values if v is not None and math.isfinite(v)], dtype=float)
    if finite.size < 2:
        return None
    half = float(stats.t.ppf(0.975, finite.size - 1) * finite.std(ddof=1) / math.sqrt(finite.size))
    mean = float(finite.mean())
    return (mean - half, mean + half)


def bootstrap_intervals(
    episodes: Sequence[Any],
    summarise: Callable[[list[Any]], dict[str, Any]],
    *,
    resamples: int = RESAMPLES,
    seed: int = 0,
) -> dict[str, tuple[float, float] | None]:
    """Percentile bootstrap 95 % interval of every INTERVAL_FIGURES entry of
    ``summarise(episodes)``; None for a figure defined in under half the resamples (or with no
    episodes)."""
    if not episodes:
        return dict.fromkeys(INTERVAL_FIGURES)
    rng = np.random.default_rng(seed)
    count = len(episodes)
    draws: dict[str, list[float]] = {key: [] for key in INTERVAL_FIGURES}
    for _ in range(resamples):
        picked = [episodes[i] for i in rng.integers(0, count, count)]
        summary = summarise(picked)
        for key in INTERVAL_FIGURES:
            value = summary.get(key)
            if value is not None and math.isfinite(value):
                draws[key].append(float(value))
    out: dict[str, tuple[float, float] | None] = {}
    for key, values in draws.items():
        if len(values) < resamples / 2:
            out[key] = None
        else:
            low, high = np.percentile(values, [2.5, 97.5])
            out[key] = (float(low), float(high))
    return out


def across_seeds(summaries: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """One summary of several training seeds' evaluations: each figure's mean over the seeds
    (None where no seed has it), ``interval95`` by ``seed_interval``, and ``training_seeds``."""
    out: dict[str, Any] = {
        "episodes": summaries[0]["episodes"],
        "training_seeds": len(summaries),
        "successes": sum(s["successes"] for s in summaries),
    }
    intervals: dict[str, tuple[float, float] | None] = {}
    for key in INTERVAL_FIGURES:
        values = [s[key] for s in summaries if s.get(key) is not None]
        out[key] = float(np.mean(values)) if values else None
        intervals[key] = seed_interval(values)
    out["interval95"] = intervals
    out["interval_over"] = "training seeds"
    return out


def replace_episodes(result: Any, episodes: list[Any]) -> Any:
    """``result`` (an EvalResult) with other episodes: what a bootstrap resample summarises."""
    return dataclasses.replace(result, episodes=episodes)


__all__ = [
    "INTERVAL_FIGURES",
    "RESAMPLES",
    "across_seeds",
    "bootstrap_intervals",
    "replace_episodes",
    "seed_interval",
]
