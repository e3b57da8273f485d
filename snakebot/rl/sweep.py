"""The trials of ``rl compare``: encodings x seeds x a grid of settings, and their table.

A ``SweepPlan`` names every trial and the folder it trains into (``OUT/ENCODING`` for one seed
and no grid, as ``rl compare`` always did; ``OUT/ENCODING[/GRID-POINT][/seed-S]`` otherwise)
and gives its ``TrainSettings``; the local loop (``compare.py``) and the Ray executor
(``compare_ray.py``) run the same trials, so ``comparison_table`` is the same for both.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from snakebot.errors import ConfigError
from snakebot.rl.resume import PPO_SETTINGS, check_ppo
from snakebot.rl.settings import (
    GOAL_ENV_ID,
    GoalSettings,
    VelocitySettings,
    settings_dict,
    split_kwargs,
)
from snakebot.rl.train import (
    ROLLOUT_STEPS,
    CurvePoint,
    TrainResult,
    TrainSettings,
    dump_json,
)

Value = float | int | str


@dataclass(frozen=True)
class Trial:
    """One training run of a sweep: an encoding, a seed and a grid point (``(key, value)``
    pairs, PPO or env settings); ``name`` is its folder under the sweep's output folder."""

    name: str
    encoding: str
    seed: int
    point: tuple[tuple[str, Value], ...] = ()


@dataclass(frozen=True)
class SweepPlan:
    """Every trial of ``rl compare``: each encoding of ``runs`` (its env kwargs, every default
    filled in) x ``seeds`` x every point of ``grid`` (key -> values; a key is a PPO setting or
    a scalar env setting; the points are the Cartesian product in the order given), each
    trained for ``steps`` env steps on ``n_envs`` envs vectorised ``vec`` with PPO settings
    ``ppo`` (the grid point's replace them). Raises ConfigError naming a bad grid key or value.
    """

    env_id: str
    runs: Mapping[str, Mapping[str, Any]]
    steps: int
    seeds: tuple[int, ...] = (0,)
    grid: Mapping[str, tuple[Value, ...]] = field(default_factory=dict)
    n_envs: int = 1
    vec: str = "dummy"
    rollout_steps: int = ROLLOUT_STEPS
    ppo: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.runs:
            raise ConfigError("runs", "", "expected at least one encoding")
        if not self.seeds or len(set(self.seeds)) != len(self.seeds):
            raise ConfigError("seeds", "", f"expected distinct seeds, got {self.seeds!r}")
        for key, values in self.grid.items():
            if not values or len(set(values)) != len(values):
                raise ConfigError("grid", key, f"expected distinct values, got {values!r}")
            if key in ("robot", "encoding"):
                raise ConfigError("grid", key, "the encodings are a sweep's own axis")
        for trial in self.trials():  # every point is checked before anything trains
            self.settings(trial)

    def trials(self) -> list[Trial]:
        """Every trial, encodings outermost, then grid points, then seeds."""
        keys = list(self.grid)
        points = [tuple(zip(keys, values, strict=True)) for values in self._products()]
        out = []
        for encoding in self.runs:
            for point in points:
                for seed in self.seeds:
                    parts = [encoding]
                    if point:
                        parts.append(",".join(f"{k}={v}" for k, v in point))
                    if len(self.seeds) > 1:
                        parts.append(f"seed-{seed}")
                    out.append(Trial("/".join(parts), encoding, seed, point))
        return out

    def _products(self) -> list[tuple[Value, ...]]:
        return list(itertools.product(*self.grid.values()))

    def settings(self, trial: Trial) -> TrainSettings:
        """The TrainSettings of ``trial``; ConfigError naming ``grid`` and the key for a value
        its setting refuses."""
        ppo = dict(self.ppo)
        env = dict(self.runs[trial.encoding])
        for key, value in trial.point:
            if key in PPO_SETTINGS:
                check_ppo({key: value}, "grid")
                ppo[key] = value
            elif key in env:
                env[key] = value
            else:
                raise ConfigError(
                    "grid",
                    key,
                    "expected a PPO setting or an env setting, one of "
                    f"{', '.join(sorted(set(PPO_SETTINGS) | set(env) - {'robot', 'encoding'}))}",
                )
        if trial.point:
            task = GoalSettings if self.env_id == GOAL_ENV_ID else VelocitySettings
            try:
                env = settings_dict(*split_kwargs(env, task))
            except ConfigError as exc:
                raise ConfigError("grid", exc.key or exc.source, exc.reason) from None
        return TrainSettings(
            self.env_id,
            env,
            self.steps,
            self.n_envs,
            self.vec,
            seed=trial.seed,
            rollout_steps=self.rollout_steps,
            ppo=ppo,
        )


@dataclass(frozen=True)
class TrialOutcome:
    """What one trial left: its training result, and whether a scheduler stopped it early
    (then ``result.curve`` ends where it stopped and its folder holds only the curve)."""

    trial: Trial
    result: TrainResult
    stopped_early: bool = False


def run_summary(outcome: TrialOutcome) -> dict[str, Any]:
    """One trial's entry in compare.json: ``dump_json`` of its run, its axes and early stop."""
    return {
        **dump_json(outcome.result),
        "encoding": outcome.trial.encoding,
        "seed": outcome.trial.seed,
        "grid": dict(outcome.trial.point),
        "stopped_early": outcome.stopped_early,
    }


def comparison_rows(outcomes: list[TrialOutcome]) -> list[dict[str, Any]]:
    """One row per encoding x grid point, over its seeds: trials, how many a scheduler stopped
    early, the mean final steps, and the mean (and standard deviation) over seeds of the final
    mean return and success rate (None where no seed has one). Wall and CPU time stay out: they
    differ from run to run, the rest does not for a given machine."""
    groups: dict[tuple[str, tuple[tuple[str, Value], ...]], list[TrialOutcome]] = {}
    for outcome in outcomes:
        groups.setdefault((outcome.trial.encoding, outcome.trial.point), []).append(outcome)
    rows = []
    for (encoding, point), members in groups.items():
        finals = [_last(o.result.curve) for o in members]
        returns = [p.mean_return for p in finals if p is not None]
        rates = [p.success_rate for p in finals if p is not None]
        rows.append(
            {
                "encoding": encoding,
                "grid": dict(point),
                "seeds": [o.trial.seed for o in members],
                "stopped_early": sum(o.stopped_early for o in members),
                "steps": float(np.mean([o.result.steps for o in members])),
                "final_mean_return": _mean(returns),
                "final_mean_return_sd": _sd(returns),
                "final_success_rate": _mean(rates),
            }
        )
    return rows


def _last(curve: list[CurvePoint]) -> CurvePoint | None:
    return curve[-1] if curve else None


def _mean(values: list[float]) -> float | None:
    finite = [v for v in values if math.isfinite(v)]
    return float(np.mean(finite)) if finite else None


def _sd(values: list[float]) -> float | None:
    finite = [v for v in values if math.isfinite(v)]
    return float(np.std(finite)) if len(finite) > 1 else None


def comparison_table(rows: list[dict[str, Any]]) -> str:
    """``comparison_rows`` as the text table ``rl compare`` prints (return with its standard
    deviation over seeds, success in %, "n/a" where undefined)."""

    def number(value: float | None, spec: str) -> str:
        return "n/a" if value is None else format(value, spec)

    header = ["encoding", "grid", "seeds", "stopped", "steps", "return", "± sd", "success"]
    lines = [header]
    for row in rows:
        rate = row["final_success_rate"]
        lines.append(
            [
                row["encoding"],
                ",".join(f"{k}={v}" for k, v in row["grid"].items()) or "-",
                str(len(row["seeds"])),
                str(row["stopped_early"]),
                f"{row['steps']:.0f}",
                number(row["final_mean_return"], ".2f"),
                number(row["final_mean_return_sd"], ".2f"),
                "n/a" if rate is None else f"{100 * rate:.0f}%",
            ]
        )
    widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
    text = []
    for line in lines:
        cells = [
            cell.ljust(width) if i < 2 else cell.rjust(width)
            for i, (cell, width) in enumerate(zip(line, widths, strict=True))
        ]
        text.append("  ".join(cells).rstrip())
    return "\n".join(text) + "\n"
