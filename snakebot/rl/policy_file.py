"""A trained policy on disk: its actor as plain numpy, and the env settings that made it.

A policy folder holds ``policy.json`` (the env id and every env setting, the training settings
and results) and ``actor.npz`` (the deterministic actor: dense layers and their activation).
Playing a policy needs only numpy; ``policy.zip`` (the stable-baselines3 model, for further
training) sits beside them when ``rl train`` wrote the folder.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from snakebot.errors import ConfigError, OutputError
from snakebot.gaits.base import FloatArray

SETTINGS_FILE = "policy.json"
ACTOR_FILE = "actor.npz"
MODEL_FILE = "policy.zip"
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


def write_settings(folder: Path, env_id: str, env_kwargs: dict[str, Any],
                   meta: dict[str, Any]) -> Path:
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


def load_policy(folder: Path) -> PolicyFile:
    """Read a policy folder; ConfigError naming the file and what is wrong with it."""
    settings_path = folder / SETTINGS_FILE
    actor_path = folder / ACTOR_FILE
    if not folder.is_dir():
        raise ConfigError(folder, "", "no such policy folder (expected a folder that training "
                          "wrote: `snakebot rl train --out DIR`)")
    try:
        payload = json.loads(settings_path.read_text())
    except FileNotFoundError:
        raise ConfigError(settings_path, "", "missing: not a policy folder written by "
                          "`snakebot rl train`") from None
    except (OSError, ValueError) as exc:
        raise ConfigError(settings_path, "", f"cannot read it as JSON: {exc}") from None
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise ConfigError(settings_path, "format", f"expected format {FORMAT}")
    env_id, kwargs = payload.get("env_id"), payload.get("env_kwargs")
    if not isinstance(env_id, str) or not isinstance(kwargs, dict):
        raise ConfigError(settings_path, "env_id", "expected an env id and env_kwargs")
    try:
        with np.load(actor_path) as data:
            count = sum(1 for key in data.files if key.startswith("w"))
            weights = tuple(np.asarray(data[f"w{i}"], dtype=np.float64) for i in range(count))
            biases = tuple(np.asarray(data[f"b{i}"], dtype=np.float64) for i in range(count))
            actor = NumpyActor(weights, biases, str(data["activation"]))
    except FileNotFoundError:
        raise ConfigError(actor_path, "", "missing: the policy's weights are not there") from None
    except (OSError, ValueError, KeyError) as exc:
        raise ConfigError(actor_path, "", f"not a policy actor: {exc}") from None
    if not all(np.all(np.isfinite(w)) for w in weights + biases) or not math.isfinite(
        float(sum(float(w.sum()) for w in weights))
    ):
        raise ConfigError(actor_path, "", "weights must be finite numbers")
    meta = {k: v for k, v in payload.items() if k not in ("format", "env_id", "env_kwargs")}
    return PolicyFile(folder, actor, env_id, dict(kwargs), meta)
