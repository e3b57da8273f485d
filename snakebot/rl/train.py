"""Training with stable-baselines3 PPO (the ``rl-train`` extra): progress, curve, saved policy.

The seed trained TRPO while its text says PPO; this is PPO. Each rollout of ``n_steps`` per env
is one point of the learning curve: mean return and success rate of the episodes that ended in
it, and the throughput so far.
"""

from __future__ import annotations

import csv
import json
import math
import resource
import sys
import time
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

import numpy as np

from snakebot.errors import ConfigError, OutputError
from snakebot.rl.deps import require
from snakebot.rl.policy_file import (
    ACTOR_FILE,
    CHECKPOINT_DIR,
    CURVE_FIELDS,
    CURVE_FILE,
    MODEL_FILE,
    NumpyActor,
    checkpoint_name,
    save_actor,
    write_settings,
)
from snakebot.rl.resume import ResumePoint, check_ppo, ppo_defaults

VECTORISATIONS = ("dummy", "subproc")


ROLLOUT_STEPS = 2048
"""PPO's rollout length in env steps when none is given (stable-baselines3's default)."""
CHECKPOINTS = 10
"""Actor snapshots a run keeps in CHECKPOINT_DIR, evenly spaced over its steps (``rl curve``
evaluates them deterministically)."""


@dataclass(frozen=True)
class TrainSettings:
    """One training run: PPO for ``steps`` env steps over ``n_envs`` envs vectorised ``vec``
    ("dummy": in this process, "subproc": one process each; the CLI's defaults are the fastest
    measured on two cores, docs/learning.md)."""

    env_id: str
    env_kwargs: dict[str, Any]
    steps: int
    n_envs: int
    vec: str
    seed: int = 0
    rollout_steps: int = ROLLOUT_STEPS
    algo: str = "ppo"
    ppo: dict[str, Any] = field(default_factory=dict)
    resume: ResumePoint | None = None
    checkpoints: int = CHECKPOINTS

    def __post_init__(self) -> None:
        if isinstance(self.checkpoints, bool) or not (
            isinstance(self.checkpoints, int) and self.checkpoints >= 0
        ):
            raise ConfigError(
                "checkpoints", "", f"expected a whole number >= 0, got {self.checkpoints!r}"
            )
        if self.algo != "ppo":
            raise ConfigError("algo", "", f"expected ppo, got {self.algo!r}")
        if self.vec not in VECTORISATIONS:
            raise ConfigError("vec", "", f"expected one of {', '.join(VECTORISATIONS)}")
        if self.n_envs < 1 or self.rollout_steps % self.n_envs:
            raise ConfigError(
                "n_envs",
                "",
                f"expected a divisor of the rollout "
                f"({self.rollout_steps} steps), got {self.n_envs}",
            )
        if self.steps < 1:
            raise ConfigError("steps", "", f"expected a positive count, got {self.steps}")
        check_ppo(self.ppo, "ppo")
        batch = self.ppo.get("batch_size", 2)
        if batch > self.rollout_steps:
            raise ConfigError(
                "ppo",
                "batch_size",
                f"expected at most the rollout ({self.rollout_steps} steps), got {batch}",
            )


@dataclass
class CurvePoint:
    """One learning-curve row (after a rollout)."""

    steps: int
    wall_s: float
    episodes: int
    mean_return: float
    success_rate: float
    mean_episode_steps: float
    steps_per_s: float


@dataclass
class TrainResult:
    """What a run produced: its curve, wall time and throughput, and where it saved."""

    curve: list[CurvePoint]
    wall_s: float
    steps: int
    folder: Path
    cpu_s: float = math.nan
    interrupted: bool = False
    new_steps: int | None = None  # this run's steps (a resumed run counts on from saved ones)

    @property
    def steps_per_s(self) -> float:
        """Env steps per second of wall time this run, PPO updates included."""
        taken = self.steps if self.new_steps is None else self.new_steps
        return taken / self.wall_s if self.wall_s > 0 else 0.0


def make_vec_env(env_id: str, env_kwargs: dict[str, Any], n_envs: int, vec: str, seed: int) -> Any:
    """An SB3 VecEnv of ``n_envs`` copies, in this process (dummy) or one process each."""
    sb3_vec = require("stable_baselines3.common.vec_env", "rl train")
    fns = [_env_fn(env_id, env_kwargs) for _ in range(n_envs)]
    venv = sb3_vec.SubprocVecEnv(fns) if vec == "subproc" else sb3_vec.DummyVecEnv(fns)
    venv.seed(seed)
    return venv


def _env_fn(env_id: str, env_kwargs: dict[str, Any]) -> Callable[[], Any]:
    def make() -> Any:
        import gymnasium

        import snakebot.rl  # noqa: F401  (registers the envs in a fresh worker process)

        class CpuClock(gymnasium.Wrapper):
            """Answers the CPU time of the process it runs in (a subproc worker's own)."""

            def process_cpu_s(self) -> float:
                usage = resource.getrusage(resource.RUSAGE_SELF)
                return usage.ru_utime + usage.ru_stime

        return CpuClock(gymnasium.make(env_id, **env_kwargs))

    return make


def _workers_cpu_s(venv: Any) -> float:
    """The subproc workers' CPU seconds so far, asked of each worker (they are children of
    multiprocessing's forkserver, so this process's rusage never counts them); NaN when a worker
    is gone (Ctrl-C reaches the workers too)."""
    try:
        return float(sum(venv.env_method("process_cpu_s")))
    except (EOFError, OSError):  # BrokenPipeError, ConnectionResetError included
        return math.nan


class _Tracker:
    """Episode returns and successes per env, and the curve rows written as they come."""

    def __init__(
        self,
        n_envs: int,
        csv_file: TextIO,
        progress: TextIO | None,
        total: int,
        previous: list[list[str]] | None = None,
        on_rollout: Callable[[CurvePoint], None] | None = None,
    ) -> None:
        self.on_rollout_point = on_rollout
        self.returns = np.zeros(n_envs)
        self.lengths = np.zeros(n_envs, dtype=int)
        self.done_returns: list[float] = []
        self.done_success: list[bool] = []
        self.done_lengths: list[int] = []
        self.episodes = 0
        self.curve: list[CurvePoint] = []
        self.writer = csv.writer(csv_file)
        self.writer.writerow(CURVE_FIELDS)
        self.writer.writerows(previous or [])
        # A resumed run's rows go on from the saved curve's wall time
        self.wall_offset_s = _last_wall_s(previous or [])
        self.csv_file = csv_file
        self.progress = progress
        self.total = total
        self.start = time.monotonic()

    def on_step(self, rewards: np.ndarray, dones: np.ndarray, infos: list[dict[str, Any]]) -> None:
        self.returns += rewards
        self.lengths += 1
        for i in np.flatnonzero(dones):
            self.done_returns.append(float(self.returns[i]))
            self.done_lengths.append(int(self.lengths[i]))
            if "is_success" in infos[i]:  # the goal task; the velocity task has no success
                self.done_success.append(bool(infos[i]["is_success"]))
            self.returns[i] = 0.0
            self.lengths[i] = 0
            self.episodes += 1

    def on_rollout(self, steps: int) -> None:
        wall = time.monotonic() - self.start + self.wall_offset_s
        returns, success = self.done_returns, self.done_success
        point = CurvePoint(
            steps=steps,
            wall_s=round(wall, 3),
            episodes=self.episodes,
            mean_return=float(np.mean(returns)) if returns else math.nan,
            success_rate=float(np.mean(success)) if success else math.nan,
            mean_episode_steps=float(np.mean(self.done_lengths)) if returns else math.nan,
            steps_per_s=round(steps / wall, 2) if wall > 0 else 0.0,
        )
        self.done_returns, self.done_success, self.done_lengths = [], [], []
        self.curve.append(point)
        self.writer.writerow([getattr(point, name) for name in CURVE_FIELDS])
        self.csv_file.flush()
        if self.on_rollout_point is not None:
            self.on_rollout_point(point)
        if self.progress is not None:
            ended = f"({point.episodes} episodes)" if point.episodes else "(no episode ended yet)"
            self.progress.write(
                f"  {steps:>9d}/{self.total} steps  {wall:7.0f} s  {point.steps_per_s:6.0f} "
                f"steps/s  return {_number(point.mean_return, '8.2f')}  success "
                f"{_percent(point.success_rate)}  {ended}\n"
            )
            self.progress.flush()


def _percent(value: float) -> str:
    return "  n/a" if math.isnan(value) else f"{100 * value:4.0f}%"


def _number(value: float, spec: str) -> str:
    """``value`` formatted, or "n/a" in its width when it is undefined (no episode ended)."""
    text = format(value, spec)
    return "n/a".rjust(len(text)) if math.isnan(value) else text


def _last_wall_s(rows: list[list[str]]) -> float:
    return float(rows[-1][CURVE_FIELDS.index("wall_s")]) if rows else 0.0


def train(
    settings: TrainSettings,
    folder: Path,
    *,
    progress: TextIO | None = sys.stderr,
    plot: bool = True,
    on_rollout: Callable[[CurvePoint], None] | None = None,
) -> TrainResult:
    """Train, then save policy.json, actor.npz, policy.zip, learning_curve.csv (+ .png).

    With ``settings.resume`` it goes on from that saved model's weights (and optimiser state)
    for ``settings.steps`` more steps, counting on from the steps it had; the curve keeps the
    saved rows. policy.json records every PPO setting used (stable-baselines3's defaults filled
    in). ``on_rollout`` is called with each curve point as it is written (a sweep reports it to
    its scheduler). Ctrl-C ends training early and still saves the policy learned so far
    (``interrupted``). The curve CSV is written row by row, so an interrupted run keeps what it
    measured. Raises MissingDependencyError naming the ``rl-train`` extra, ConfigError for bad
    settings or a saved model that cannot be trained on, OutputError when the folder cannot be
    written.
    """
    torch = require("torch", "rl train")
    sb3 = require("stable_baselines3", "rl train")
    callbacks = require("stable_baselines3.common.callbacks", "rl train")
    torch.set_num_threads(1)  # one core per env process; PPO's small MLP gains nothing more
    resume = settings.resume
    ppo_kwargs = {
        "n_steps": settings.rollout_steps // settings.n_envs,
        **ppo_defaults(),
        **settings.ppo,
    }
    previous = resume.curve_rows if resume is not None else []
    try:
        folder.mkdir(parents=True, exist_ok=True)
        csv_file = (folder / CURVE_FILE).open("w", newline="")
    except OSError as exc:
        reason = exc.strerror or str(exc)
        raise OutputError(folder, f"cannot write the training output: {reason}") from exc
    cpu_start = _cpu_s()
    start_steps = resume.steps if resume is not None else 0
    tracker = _Tracker(
        settings.n_envs, csv_file, progress, start_steps + settings.steps, previous, on_rollout
    )

    class Callback(callbacks.BaseCallback):  # type: ignore[misc,name-defined]
        def _on_step(self) -> bool:
            tracker.on_step(self.locals["rewards"], self.locals["dones"], self.locals["infos"])
            return True

        def _on_rollout_start(self) -> None:
            # PPO has just updated on every step so far: the actor trained on num_timesteps
            snapshots.after_update(self.model)

        def _on_rollout_end(self) -> None:
            tracker.on_rollout(int(self.num_timesteps))

    snapshots = _Snapshots(folder / CHECKPOINT_DIR, start_steps, settings)
    interrupted = False
    workers_cpu = 0.0
    try:
        venv = make_vec_env(
            settings.env_id, settings.env_kwargs, settings.n_envs, settings.vec, settings.seed
        )
        try:
            model = sb3.PPO(
                "MlpPolicy", venv, seed=settings.seed, verbose=0, device="cpu", **ppo_kwargs
            )
            if resume is not None:
                _load_weights(model, resume.model_path)
                model.num_timesteps = resume.steps
            try:
                model.learn(
                    total_timesteps=settings.steps,
                    callback=Callback(),
                    reset_num_timesteps=resume is None,
                )
            except KeyboardInterrupt:  # Ctrl-C: keep the policy learned so far
                interrupted = True
            if settings.vec == "subproc":
                workers_cpu = _workers_cpu_s(venv)
        finally:
            venv.close()
    finally:
        csv_file.close()
    wall = time.monotonic() - tracker.start
    cpu = _cpu_s() - cpu_start + workers_cpu
    steps = int(model.num_timesteps)
    model.save(folder / MODEL_FILE)
    save_actor(actor_from_sb3(model), folder / ACTOR_FILE)
    snapshots.final(model)
    last = tracker.curve[-1] if tracker.curve else None
    meta = {
        "algo": settings.algo,
        "steps": steps,
        "interrupted": interrupted,
        "seed": settings.seed,
        "n_envs": settings.n_envs,
        "vec": settings.vec,
        "ppo": ppo_kwargs,
        "wall_s": round(wall, 2),
        "cpu_s": _finite(round(cpu, 2)),
        "steps_per_s": round((steps - start_steps) / wall, 2) if wall > 0 else None,
        "final_mean_return": None if last is None else _finite(last.mean_return),
        "final_success_rate": None if last is None else _finite(last.success_rate),
        "versions": {"stable_baselines3": sb3.__version__, "torch": torch.__version__},
        "resumed_from": None
        if resume is None
        else {"folder": str(resume.folder), "steps": resume.steps},
    }
    write_settings(folder, settings.env_id, settings.env_kwargs, meta)
    result = TrainResult(tracker.curve, wall, steps, folder, cpu, interrupted, steps - start_steps)
    if plot:
        from snakebot.rl.plots import curve_plot

        rows = read_curve(folder / CURVE_FILE)  # the saved rows of a resumed run too
        curve_plot(
            {_label(settings): rows},
            folder / "learning_curve.png",
            title=f"{settings.env_id} ({settings.env_kwargs.get('encoding', '')})",
        )
    return result


class _Snapshots:
    """The run's actor snapshots: after the first update at or past each of ``checkpoints``
    evenly spaced marks of this run's steps (named by the steps it was trained on), and the
    last one at the end. A new run (not a
    resumed one) starts an empty folder: another run's snapshots would mix into its curve."""

    def __init__(self, folder: Path, start_steps: int, settings: TrainSettings) -> None:
        self.folder = folder
        self.every = settings.steps / settings.checkpoints if settings.checkpoints else math.inf
        self.next_due = start_steps + self.every
        self.start_steps = start_steps
        self.saved: set[int] = set()
        if settings.checkpoints and settings.resume is None and folder.is_dir():
            for old in folder.glob("actor-*.npz"):  # the CLI refused this without --force
                old.unlink()

    def after_update(self, model: Any) -> None:
        steps = int(model.num_timesteps)
        if steps >= self.next_due:
            self._save(model, steps)
            while self.next_due <= steps:
                self.next_due += self.every

    def final(self, model: Any) -> None:
        steps = int(model.num_timesteps)
        if math.isfinite(self.every) and steps > self.start_steps and steps not in self.saved:
            self._save(model, steps)

    def _save(self, model: Any, steps: int) -> None:
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OutputError(self.folder, f"cannot write the checkpoints: {exc.strerror}") from exc
        save_actor(actor_from_sb3(model), self.folder / checkpoint_name(steps))
        self.saved.add(steps)


def _load_weights(model: Any, path: Path) -> None:
    """The saved model's weights and optimiser state into ``model``: tensors only
    (``torch.load(weights_only=True)``), none of the zip's pickled objects."""
    import pickle

    try:
        model.set_parameters(str(path), exact_match=True, device="cpu")
    except (
        ValueError,
        RuntimeError,
        KeyError,
        OSError,
        EOFError,
        pickle.UnpicklingError,
        zipfile.BadZipFile,
    ) as exc:
        raise ConfigError(
            path,
            "",
            f"cannot train on this model (not the network this "
            f"policy's settings make): {str(exc).splitlines()[0]}",
        ) from None


def _cpu_s() -> float:
    """CPU seconds of this process and its waited-for children: all a dummy-vectorised run
    costs whatever else the machine was doing (subproc workers are asked for theirs)."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def _label(settings: TrainSettings) -> str:
    return str(settings.env_kwargs.get("encoding", settings.env_id))


def _finite(value: float) -> float | None:
    return None if math.isnan(value) else value


def actor_from_sb3(model: Any) -> NumpyActor:
    """The deterministic actor of an SB3 MlpPolicy (its policy net and action net) as numpy."""
    torch = require("torch", "rl train")
    policy = model.policy
    layers = [m for m in policy.mlp_extractor.policy_net if isinstance(m, torch.nn.Linear)]
    acts = {type(m).__name__ for m in policy.mlp_extractor.policy_net} - {"Linear"}
    activation = {"Tanh": "tanh", "ReLU": "relu"}.get(acts.pop() if acts else "Tanh")
    if activation is None:
        raise ConfigError("policy", "", "only Tanh or ReLU MLP policies can be exported")
    layers.append(policy.action_net)
    weights = tuple(m.weight.detach().cpu().numpy().astype(np.float64) for m in layers)
    biases = tuple(m.bias.detach().cpu().numpy().astype(np.float64) for m in layers)
    return NumpyActor(weights, biases, activation)


def read_curve(path: Path) -> list[CurvePoint]:
    """A learning_curve.csv back as points."""
    with path.open() as f:
        rows = list(csv.DictReader(f))
    return [
        CurvePoint(
            int(r["steps"]),
            float(r["wall_s"]),
            int(r["episodes"]),
            float(r["mean_return"]),
            float(r["success_rate"]),
            float(r["mean_episode_steps"]),
            float(r["steps_per_s"]),
        )
        for r in rows
    ]


def dump_json(result: TrainResult) -> dict[str, Any]:
    """The JSON summary of a training run."""
    last = result.curve[-1] if result.curve else None
    payload = {
        "folder": str(result.folder),
        "steps": result.steps,
        "wall_s": round(result.wall_s, 2),
        "cpu_s": _finite(round(result.cpu_s, 2)),
        "interrupted": result.interrupted,
        "steps_per_s": round(result.steps_per_s, 2),
        "final_mean_return": None if last is None else _finite(last.mean_return),
        "final_success_rate": None if last is None else _finite(last.success_rate),
    }
    json.dumps(payload)
    return payload
