"""``snakebot rl compare``: the seed's figure, learning curves of several encodings side by side.

Each encoding trains with the same steps, seed and vectorisation into its own policy folder;
``compare.png`` draws the curves together and ``compare.json`` keeps the final numbers. With
several seeds or a grid of settings every trial has its own folder (``snakebot.rl.sweep``);
an ``executor`` (``compare_ray.RayExecutor``) runs the trials elsewhere, this module runs them
one after the other here.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, TextIO

from snakebot.errors import OutputError
from snakebot.rl.plots import curve_plot
from snakebot.rl.sweep import SweepPlan, TrialOutcome, comparison_rows, run_summary
from snakebot.rl.train import ROLLOUT_STEPS, train

# Runs every trial of a plan into its folder under ``out``; the outcomes in plan order.
Executor = Callable[[SweepPlan, Path, TextIO | None], list[TrialOutcome]]


def compare(
    env_id: str,
    runs: dict[str, dict[str, Any]],
    steps: int,
    out: Path,
    *,
    seed: int,
    n_envs: int,
    vec: str,
    progress: TextIO | None = sys.stderr,
    seeds: int = 1,
    grid: dict[str, tuple[Any, ...]] | None = None,
    rollout_steps: int = ROLLOUT_STEPS,
    ppo: dict[str, Any] | None = None,
    executor: Executor | None = None,
) -> dict[str, Any]:
    """Train every ``runs[encoding]`` (env kwargs) for ``steps`` on seeds ``seed..seed+seeds-1``
    at every point of ``grid`` (``SweepPlan``); returns the summary written to
    ``out/compare.json`` beside ``out/compare.png``: ``runs`` (each trial's, by folder name)
    and ``table`` (``comparison_rows``). Raises ConfigError for a bad plan, OutputError when
    ``out`` cannot be written."""
    plan = SweepPlan(
        env_id,
        runs,
        steps,
        tuple(range(seed, seed + seeds)),
        grid or {},
        n_envs,
        vec,
        rollout_steps,
        ppo or {},
    )
    if executor is not None:
        outcomes = executor(plan, out, progress)
    else:
        outcomes = []
        for trial in plan.trials():
            if progress is not None:
                progress.write(f"{trial.name}:\n")
            result = train(plan.settings(trial), out / trial.name, progress=progress)
            outcomes.append(TrialOutcome(trial, result))
    curve_plot(
        {o.trial.name: o.result.curve for o in outcomes},
        out / "compare.png",
        title=f"{env_id}: encodings",
    )
    summary = {
        "env_id": env_id,
        "steps": steps,
        "seed": seed,
        "seeds": list(plan.seeds),
        "grid": {key: list(values) for key, values in plan.grid.items()},
        "runs": {o.trial.name: run_summary(o) for o in outcomes},
        "table": comparison_rows(outcomes),
    }
    path = out / "compare.json"
    try:
        path.write_text(json.dumps(summary, indent=2) + "\n")
    except OSError as exc:
        raise OutputError(path, f"cannot write the summary: {exc.strerror or exc}") from exc
    return summary
