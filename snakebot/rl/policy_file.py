"""A trained policy on disk: its actor as plain numpy, and the env settings that made it.

A policy folder holds ``policy.json`` (the env id and every env setting, the training settings
and results) and ``actor.npz`` (the deterministic actor: dense layers and their activation).
Playing a policy needs only numpy; ``policy.zip`` (the stable-baselines3 model, for further
training) sits beside them when ``rl train`` wrote the folder.
"""

from __future__ import annotations

import json
import math
import zipfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from snakebot.config import load_robot
from snakebot.errors import ConfigError, OutputError
from snakebot.gaits.base import FloatArray
from snakebot.rl.settings import (
    ENV_IDS,
    GOAL_ENV_ID,
    EnvSettings,
    GoalSettings,
    VelocitySettings,
    split_kwargs,
)

SETTINGS_FILE = "policy.json"
ACTOR_FILE = "actor.npz"
MODEL_FILE = "policy.zip"
CURVE_FILE = "learning_curve.csv"
CURVE_FIELDS = (
    "steps",
    "wall_s",
    "episodes",
    "mean_return",
    "success_rate",
    "mean_episode_steps",
    "steps_per_s",
)
# Every file `rl train` writes into its folder: what a second run there would replace.
CHECKPOINT_DIR = "checkpoints"
"""Where training keeps its actor snapshots: actor-STEPS.npz (``checkpoint_name``)."""
TRAIN_FILES = (
    SETTINGS_FILE,
    ACTOR_FILE,
    MODEL_FILE,
    CURVE_FILE,
    "learning_curve.png",
    CHECKPOINT_DIR,
)
FORMAT = 1
ACTIVATIONS = ("tanh", "relu")


@dataclass(frozen=True)
class NumpyActor:
    """obs (D,) -> action (d,) in [-1, 1]: hidden dense layers with ``activation``, a linear
    output, clipped. ``weights[i]`` has shape (out, in), ``biases[i]`` (out,)."""

    weights: tuple[FloatArray, ...]
    biases: tuple[FloatArray, ...]
    activation: str = "tanh"

    def __post_init__(self) -> None:
        if self.activation not in ACTIVATIONS:
            raise ValueError(f"activation must be one of {ACTIVATIONS}, got {self.activation!r}")
        if not self.weights or len(self.weights) != len(self.biases):
            raise ValueError("expected as many bias vectors as weight matrices, at least one")
        for i, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            if w.ndim != 2 or b.shape != (w.shape[0],) or 0 in w.shape:
                raise ValueError(
                    f"layer {i}: expected weights (out, in) and biases (out,), got "
                    f"{w.shape} and {b.shape}"
                )
            if i and w.shape[1] != self.weights[i - 1].shape[0]:
                raise ValueError(
                    f"layer {i} takes {w.shape[1]} inputs, layer {i - 1} gives "
                    f"{self.weights[i - 1].shape[0]}"
                )

    @property
    def obs_dim(self) -> int:
        """D, the observation length."""
        return int(self.weights[0].shape[1])

    @property
    def action_dim(self) -> int:
        """d, the action length."""
        return int(self.weights[-1].shape[0])

    def __call__(self, obs: np.ndarray) -> FloatArray:
        """The deterministic action for one observation (D,)."""
        h = np.asarray(obs, dtype=np.float64)
        last = len(self.weights) - 1
        for i, (w, b) in enumerate(zip(self.weights, self.biases, strict=True)):
            h = w @ h + b
            if i < last:
                h = np.tanh(h) if self.activation == "tanh" else np.maximum(h, 0.0)
        return np.clip(h, -1.0, 1.0)


def checkpoint_name(steps: int) -> str:
    """The file name of the actor snapshot taken at ``steps`` env steps."""
    return f"actor-{steps:010d}.npz"


def checkpoint_steps(path: Path) -> int | None:
    """The env steps of a snapshot file named by ``checkpoint_name``; None for another name."""
    stem = path.name.removeprefix("actor-").removesuffix(".npz")
    if not stem.isdigit() or path.name != checkpoint_name(int(stem)):
        return None
    return int(stem)


def save_actor(actor: NumpyActor, path: Path) -> None:
    """Write ``actor`` as an npz file."""
    arrays: dict[str, Any] = {"activation": np.array(actor.activation)}
    for i, (w, b) in enumerate(zip(actor.weights, actor.biases, strict=True)):
        arrays[f"w{i}"], arrays[f"b{i}"] = w, b
    try:
        np.savez(path, **arrays)
    except OSError as exc:
        raise OutputError(path, f"cannot write the policy: {exc.strerror or exc}") from exc


@dataclass(frozen=True)
class PolicyFile:
    """A loaded policy folder: the actor, the env id and settings (kwargs for gymnasium.make),
    and whatever else training recorded."""

    folder: Path
    actor: NumpyActor
    env_id: str
    env_kwargs: dict[str, Any]
    meta: dict[str, Any]


def write_settings(
    folder: Path, env_id: str, env_kwargs: dict[str, Any], meta: dict[str, Any]
) -> Path:
    """Write policy.json into ``folder``."""
    path = folder / SETTINGS_FILE
    payload = {"format": FORMAT, "env_id": env_id, "env_kwargs": env_kwargs, **meta}
    try:
        path.write_text(json.dumps(payload, indent=2, default=_jsonable) + "\n")
    except OSError as exc:
        raise OutputError(path, f"cannot write the policy settings: {exc.strerror or exc}") from exc
    return path


def _jsonable(value: object) -> object:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.floating | np.integer):
        return value.item()
    raise TypeError(f"not JSON-ready: {type(value).__name__}")


def check_env_id(source: str | Path, env_id: object) -> str:
    """``env_id`` when it names one of snakebot's registered environments; ConfigError naming
    ``source`` and ``env_id`` otherwise.

    The one check of an env id read from a policy folder (``rl eval``, ``run --policy`` and their
    dry runs all load through ``load_policy``). A policy folder is data people share: gymnasium
    would import the module of a ``module:Env-v0`` id, so nothing but snakebot's own ids is ever
    handed to it, and nothing is imported by a name from a file.
    """
    if not isinstance(env_id, str) or env_id not in ENV_IDS:
        raise ConfigError(
            source,
            "env_id",
            f"expected one of {', '.join(ENV_IDS)}, got "
            f"{env_id!r}: a policy folder names only snakebot's own environments "
            "(nothing named in it is imported)",
        )
    return env_id


def _count(minimum: int) -> Callable[[object], bool]:
    return lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= minimum


def _number_or_null(value: object) -> bool:
    return value is None or (isinstance(value, int | float) and not isinstance(value, bool))


# What training records beside the env settings; any other key is refused (a typo, or a file
# that is not ours). Each value is checked for the type that reading it back relies on.
META_KEYS: dict[str, Callable[[object], bool]] = {
    "algo": lambda v: isinstance(v, str),
    "steps": _count(0),
    "interrupted": lambda v: isinstance(v, bool),
    "seed": _count(-(2**63)),
    "n_envs": _count(1),
    "vec": lambda v: v in ("dummy", "subproc"),
    "ppo": lambda v: isinstance(v, dict),
    "wall_s": _number_or_null,
    "cpu_s": _number_or_null,
    "steps_per_s": _number_or_null,
    "final_mean_return": _number_or_null,
    "final_success_rate": _number_or_null,
    "versions": lambda v: isinstance(v, dict),
    "resumed_from": lambda v: v is None or isinstance(v, dict),
    "action": lambda v: isinstance(v, list),  # tools/rl_open_loop.py: its one constant action
}
MAX_DEPTH = 8  # policy.json nests two levels; far deeper is not a file training wrote


def _check_values(path: Path, payload: dict[str, Any]) -> None:
    """ConfigError naming the key path of the first non-finite number or too-deep nesting."""
    todo: list[tuple[str, object, int]] = [(k, v, 1) for k, v in payload.items()]
    while todo:
        key, value, depth = todo.pop()
        if depth > MAX_DEPTH:
            raise ConfigError(path, key, f"nested more than {MAX_DEPTH} levels deep")
        if isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(path, key, f"expected a finite number, got {value!r}")
        if isinstance(value, dict):
            todo += [(f"{key}.{k}", v, depth + 1) for k, v in value.items()]
        elif isinstance(value, list):
            todo += [(f"{key}[{i}]", v, depth + 1) for i, v in enumerate(value)]


def _read_json(path: Path) -> dict[str, Any]:
    try:
        payload = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ConfigError(
            path, "", "missing: not a policy folder written by `snakebot rl train`"
        ) from None
    except RecursionError:
        raise ConfigError(path, "", f"nested more than {MAX_DEPTH} levels deep") from None
    except (OSError, ValueError) as exc:  # UnicodeDecodeError and JSONDecodeError included
        raise ConfigError(path, "", f"cannot read it as JSON: {exc}") from None
    if not isinstance(payload, dict):
        raise ConfigError(path, "", "expected a JSON object of settings")
    return payload


def read_settings(folder: Path) -> tuple[str, dict[str, Any], dict[str, Any]]:
    """The env id, env kwargs (every setting checked) and training record of policy.json in
    ``folder``; ConfigError naming the file and the key path of what is wrong."""
    path = folder / SETTINGS_FILE
    if not folder.is_dir():
        raise ConfigError(
            folder,
            "",
            "no such policy folder (expected a folder that training "
            "wrote: `snakebot rl train --out DIR`)",
        )
    payload = _read_json(path)
    _check_values(path, payload)
    if payload.get("format") != FORMAT:
        raise ConfigError(
            path, "format", f"expected format {FORMAT}, got {payload.get('format')!r}"
        )
    env_id = check_env_id(path, payload.get("env_id"))
    kwargs = payload.get("env_kwargs")
    if not isinstance(kwargs, dict):
        raise ConfigError(path, "env_kwargs", "expected an object of env settings")
    meta = {k: v for k, v in payload.items() if k not in ("format", "env_id", "env_kwargs")}
    for key, value in meta.items():
        check = META_KEYS.get(key)
        if check is None:
            raise ConfigError(
                path,
                key,
                f"unknown key; expected format, env_id, env_kwargs or {', '.join(META_KEYS)}",
            )
        if not check(value):
            raise ConfigError(path, key, f"not what training writes there: {value!r}")
    task = GoalSettings if env_id == GOAL_ENV_ID else VelocitySettings
    try:
        split_kwargs(kwargs, task)
    except ConfigError as exc:
        raise ConfigError(path, f"env_kwargs.{exc.source}", exc.reason) from None
    try:
        load_robot(kwargs.get("robot", EnvSettings.robot))
    except ConfigError as exc:
        raise ConfigError(path, "env_kwargs.robot", str(exc)) from None
    return env_id, dict(kwargs), meta


def load_actor(path: Path) -> NumpyActor:
    """actor.npz back as a NumpyActor; ConfigError naming the file when it is not one."""
    try:
        with np.load(path, allow_pickle=False) as data:
            count = sum(1 for key in data.files if key.startswith("w"))
            weights = tuple(np.asarray(data[f"w{i}"], dtype=np.float64) for i in range(count))
            biases = tuple(np.asarray(data[f"b{i}"], dtype=np.float64) for i in range(count))
            actor = NumpyActor(weights, biases, str(data["activation"]))
    except FileNotFoundError:
        raise ConfigError(path, "", "missing: the policy's weights are not there") from None
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, AttributeError) as exc:
        raise ConfigError(path, "", f"not a policy actor: {exc}") from None
    if not all(np.all(np.isfinite(w)) for w in weights + biases):
        raise ConfigError(path, "", "weights must be finite numbers")
    return actor


def load_policy(folder: Path) -> PolicyFile:
    """Read a policy folder; ConfigError naming the file and what is wrong with it.

    Everything is checked before anything runs: the env id is one of snakebot's (``check_env_id``),
    every env setting and training record has the type and range training writes, and the actor
    is a dense network of finite weights. Nothing in the folder is imported or unpickled.
    """
    env_id, kwargs, meta = read_settings(folder)
    actor = load_actor(folder / ACTOR_FILE)
    return PolicyFile(folder, actor, env_id, kwargs, meta)
