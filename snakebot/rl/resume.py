"""What a training run records of PPO and what ``rl train --resume`` reads back to go on.

``PPO_SETTINGS`` are the stable-baselines3 PPO settings policy.json records (every one, SB3's
defaults filled in) and ``--ppo KEY=VALUE`` changes; ``resume_point`` checks a saved policy
folder for what continuing needs (its settings, the model zip, the learning curve so far).
"""

from __future__ import annotations

import csv
import math
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from snakebot.errors import ConfigError
from snakebot.rl.deps import require
from snakebot.rl.policy_file import (
    CURVE_FIELDS,
    CURVE_FILE,
    MODEL_FILE,
    SETTINGS_FILE,
    read_settings,
)


def _real(
    low: float, high: float = math.inf, *, low_open: bool = False
) -> Callable[[object], bool]:
    def check(v: object) -> bool:
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            return False
        return (v > low if low_open else v >= low) and v <= high

    return check


def _whole(low: int) -> Callable[[object], bool]:
    return lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= low


# The PPO settings a run records in policy.json and ``rl train --ppo KEY=VALUE`` changes (SB3's
# names; n_steps is the rollout over the envs). What each must be, said when it is not.
PPO_SETTINGS: dict[str, tuple[Callable[[object], bool], str]] = {
    "learning_rate": (_real(0.0, 1.0), "a number in 0..1"),
    "batch_size": (_whole(2), "a whole number of at least 2"),
    "n_epochs": (_whole(1), "a whole number of at least 1"),
    "gamma": (_real(0.0, 1.0), "a number in 0..1"),
    "gae_lambda": (_real(0.0, 1.0), "a number in 0..1"),
    "clip_range": (_real(0.0, 10.0, low_open=True), "a number in (0, 10]"),
    "ent_coef": (_real(0.0, 1e3), "a number of at least 0"),
    "vf_coef": (_real(0.0, 1e3), "a number of at least 0"),
    "max_grad_norm": (_real(0.0, 1e6, low_open=True), "a positive number"),
}


def check_ppo(values: dict[str, Any], source: str | Path, prefix: str = "") -> dict[str, Any]:
    """``values`` when every key is a PPO setting of the right kind; ConfigError naming
    ``source`` and ``prefix + key`` otherwise (``n_steps`` is accepted and dropped: the rollout
    over the envs sets it)."""
    out: dict[str, Any] = {}
    for key, value in values.items():
        if key == "n_steps":
            continue
        if key not in PPO_SETTINGS:
            raise ConfigError(
                source,
                f"{prefix}{key}",
                f"unknown PPO setting; expected one of {', '.join(PPO_SETTINGS)}",
            )
        check, expected = PPO_SETTINGS[key]
        if not check(value):
            raise ConfigError(source, f"{prefix}{key}", f"expected {expected}, got {value!r}")
        out[key] = value
    return out


def ppo_defaults() -> dict[str, Any]:
    """Stable-baselines3's own PPO defaults for every setting in PPO_SETTINGS."""
    import inspect

    sb3 = require("stable_baselines3", "rl train")
    parameters = inspect.signature(sb3.PPO.__init__).parameters
    return {key: parameters[key].default for key in PPO_SETTINGS}


@dataclass(frozen=True)
class ResumePoint:
    """A saved policy to train on: its env, its recorded PPO settings, the steps it has and its
    learning-curve rows so far (text, as written)."""

    folder: Path
    env_id: str
    env_kwargs: dict[str, Any]
    ppo: dict[str, Any]
    steps: int
    rollout_steps: int
    curve_rows: list[list[str]]

    @property
    def model_path(self) -> Path:
        """The stable-baselines3 model whose weights training continues from."""
        return self.folder / MODEL_FILE


def resume_point(folder: Path) -> ResumePoint:
    """What ``folder`` (written by ``rl train``) holds to go on training; ConfigError naming the
    file and key when something is missing or not what training wrote."""
    env_id, kwargs, meta = read_settings(folder)
    settings = folder / SETTINGS_FILE
    model = folder / MODEL_FILE
    if not model.is_file():
        raise ConfigError(
            model, "", "missing: the model to train on (rl train writes it beside policy.json)"
        )
    if not zipfile.is_zipfile(model):
        raise ConfigError(model, "", "not a stable-baselines3 model (not a zip file)")
    for key in ("steps", "n_envs", "ppo"):
        if key not in meta:
            raise ConfigError(settings, key, "missing: not a policy folder `rl train` wrote")
    recorded = dict(meta["ppo"])
    ppo = check_ppo(recorded, settings, "ppo.")
    n_steps = recorded.get("n_steps", 2048)
    if not _whole(1)(n_steps):
        raise ConfigError(settings, "ppo.n_steps", f"expected a whole number, got {n_steps!r}")
    curve = folder / CURVE_FILE
    rows: list[list[str]] = []
    if curve.is_file():
        try:
            with curve.open(newline="", encoding="utf-8") as f:
                rows = list(csv.reader(f))
        except (OSError, ValueError, csv.Error) as exc:
            raise ConfigError(curve, "", f"cannot read the learning curve: {exc}") from None
        if not rows or tuple(rows[0]) != CURVE_FIELDS:
            raise ConfigError(curve, "", f"expected the header {','.join(CURVE_FIELDS)}")
        rows = rows[1:]
        for i, row in enumerate(rows, start=2):
            try:
                if len(row) != len(CURVE_FIELDS) or any(math.isinf(float(v)) for v in row):
                    raise ValueError(row)
            except ValueError:
                raise ConfigError(
                    curve, f"line {i}", f"expected {len(CURVE_FIELDS)} numbers, got {row!r}"
                ) from None
    return ResumePoint(
        folder, env_id, kwargs, ppo, int(meta["steps"]), int(n_steps) * int(meta["n_envs"]), rows
    )


__all__ = ["PPO_SETTINGS", "ResumePoint", "check_ppo", "ppo_defaults", "resume_point"]
