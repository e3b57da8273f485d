"""``rl compare --executor ray``: the trials of a sweep as Ray Tune trials (the ``cluster`` extra).

Each trial trains on a worker (``train`` as the local loop calls it, into a temporary folder)
and reports every rollout's curve point; its whole policy folder comes back as its Tune
checkpoint, which the driver copies to ``OUT/TRIAL`` where a local run writes it, so the
comparison is the local one's. ``--scheduler asha`` stops trials whose mean return falls behind
at a rung (their folder keeps the curve up to there); a trial whose worker died is run again
from the start (a resumed PPO run would not be bit for bit the uninterrupted one); the Tune
experiment in ``OUT/ray-tune`` lets ``--resume`` go on after Ctrl-C or a lost driver, keeping
the trials that finished.
"""

from __future__ import annotations

import contextlib
import csv
import importlib
import json
import math
import os
import re
import shutil
import sys
import tempfile
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, TextIO

from snakebot.cluster import INSTALL, ray_session, require_ray
from snakebot.errors import ConfigError, MissingDependencyError, SweepError
from snakebot.rl.policy_file import CURVE_FIELDS, CURVE_FILE, read_settings
from snakebot.rl.sweep import SweepPlan, Trial, TrialOutcome
from snakebot.rl.train import CurvePoint, TrainResult, TrainSettings, read_curve, train

EXPERIMENT = "ray-tune"  # OUT/ray-tune: the Tune experiment, what --resume goes on from
PLAN_FILE = "snakebot-plan.json"  # in it: the trials it was started with
SCHEDULERS = ("none", "asha")
ASHA_REDUCTION = 2  # each rung keeps the better half: a gentle cut for sweeps of a few trials


@dataclass(frozen=True)
class RayOptions:
    """How a sweep runs on Ray.

    ``address``: a running cluster (``HOST:PORT``); None starts Ray on this machine with
    ``num_cpus`` CPUs (None: all), on 127.0.0.1 only (``snakebot.cluster.connect``).
    ``scheduler``: "none" or "asha" (stops trials whose mean return at a rung of
    ``asha_grace_steps`` x 2^k env steps is in the worse half; None: a quarter of the trial's
    steps, at least one rollout). ``cpus_per_trial``: None gives ``n_envs`` for subproc envs, 1
    for dummy ones. ``max_concurrent_trials``: None lets Ray run as many as fit. ``retries``:
    how often a failed trial (a lost node) runs again. ``resume``: go on with the experiment in
    ``OUT/ray-tune``.
    """

    address: str | None = None
    num_cpus: int | None = None
    scheduler: str = "none"
    asha_grace_steps: int | None = None
    cpus_per_trial: float | None = None
    max_concurrent_trials: int | None = None
    retries: int = 2
    resume: bool = False

    def __post_init__(self) -> None:
        if self.scheduler not in SCHEDULERS:
            raise ConfigError("scheduler", self.scheduler, f"expected {' or '.join(SCHEDULERS)}")
        if self.asha_grace_steps is not None and self.scheduler != "asha":
            raise ConfigError("asha_grace_steps", "", "sets the asha scheduler's first rung")
        if self.cpus_per_trial is not None and not self.cpus_per_trial > 0:
            raise ConfigError("cpus_per_trial", str(self.cpus_per_trial), "expected > 0")
        if self.num_cpus is not None and self.address is not None:
            raise ConfigError("num_cpus", "", "sizes the Ray started here, not a cluster's")
        if self.retries < 0:
            raise ConfigError("retries", str(self.retries), "expected 0 or more")


def require_tune() -> Any:
    """``ray`` with Tune, usage statistics and Tune's own tables off; MissingDependencyError
    with the install command when either is missing."""
    os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")
    os.environ.setdefault("RAY_AIR_NEW_OUTPUT", "0")  # Tune's tables off: compare prints its own
    # Tune warns when a sweep of short trials snapshots its state often; that is the point here
    os.environ.setdefault("TUNE_WARN_EXCESSIVE_EXPERIMENT_CHECKPOINT_SYNC_THRESHOLD_S", "0")
    ray = require_ray()
    try:
        importlib.import_module("ray.tune")
    except ImportError as exc:
        raise MissingDependencyError(f"the Ray sweeps need Ray Tune: {INSTALL}") from exc
    return ray


def trial_config(trial: Trial, settings: TrainSettings) -> dict[str, Any]:
    """What a worker needs to train ``trial``: its name and its TrainSettings as plain data."""
    fields = asdict(settings)
    fields.pop("resume")
    return {"name": trial.name, "settings": fields}


def run_trial(config: dict[str, Any]) -> None:
    """A Tune function trainable (``config["trial"]``: ``trial_config``): train one trial,
    report each rollout's curve point (the scheduler's ``steps`` and ``mean_return``), then its
    policy folder as the checkpoint."""
    from ray import tune

    settings = TrainSettings(**config["trial"]["settings"])
    with tempfile.TemporaryDirectory(prefix="snakebot-trial-") as tmp:
        folder = Path(tmp) / "policy"
        result = train(
            settings,
            folder,
            progress=None,
            on_rollout=lambda point: tune.report({**asdict(point), "finished": False}),
        )
        last = asdict(result.curve[-1]) if result.curve else {}
        tune.report(
            {**last, "finished": not result.interrupted},
            checkpoint=tune.Checkpoint.from_directory(str(folder)),
        )


def trial_name(trial: Any) -> str:
    """Tune's name of a trial: its folder name under OUT."""
    return str(trial.config["trial"]["name"])


def trial_dirname(trial: Any) -> str:
    """The trial's folder in the Tune experiment: its name made path-safe, and its id."""
    return re.sub(r"[^\w.=,-]", "_", trial_name(trial)) + f"_{trial.trial_id}"


class RayExecutor:
    """Runs a ``SweepPlan``'s trials on Ray Tune and copies each policy folder to ``OUT/TRIAL``
    (the ``compare`` executor hook)."""

    def __init__(self, options: RayOptions) -> None:
        self.options = options

    def __call__(self, plan: SweepPlan, out: Path, progress: TextIO | None) -> list[TrialOutcome]:
        """Run every trial; their outcomes in plan order. Raises SweepError when a trial
        failed every try, KeyboardInterrupt when the sweep was interrupted (``--resume`` goes
        on), ConfigError naming ``resume`` when there is no experiment to resume or it has
        another plan. Without
        ``resume`` an experiment already in ``OUT/ray-tune`` is replaced (the CLI refuses that
        without ``--force``)."""
        trials = plan.trials()
        configs = [trial_config(t, plan.settings(t)) for t in trials]
        experiment = out.resolve() / EXPERIMENT
        self._check_experiment(experiment, configs)
        cpus = self.options.cpus_per_trial or (plan.n_envs if plan.vec == "subproc" else 1)
        ray = require_tune()
        # Ray prints its workers' output and the cluster's errors (a node marked dead) to
        # stdout; they go to stderr, so stdout keeps only the table or the --json summary.
        with (
            contextlib.redirect_stdout(sys.stderr),
            ray_session(self.options.address, num_cpus=self.options.num_cpus),
        ):
            from ray import tune

            _check_cpus(ray, cpus)
            trainable = tune.with_resources(run_trial, {"cpu": cpus})
            if self.options.resume:
                tuner = tune.Tuner.restore(
                    str(experiment), trainable, resume_unfinished=True, resume_errored=True
                )
            else:
                experiment.mkdir(parents=True, exist_ok=True)
                (experiment / PLAN_FILE).write_text(json.dumps(configs, indent=1) + "\n")
                tuner = self._tuner(tune, trainable, plan, configs, out, progress is not None)
            grid = tuner.fit()
            if _unfinished(tune, experiment):  # Tune ended the run on Ctrl-C
                if progress is not None:
                    progress.write(
                        f"interrupted: the same rl compare with --resume goes on with the "
                        f"unfinished trials in {out}\n"
                    )
                raise KeyboardInterrupt
            return self._land(grid, trials, out)

    def _check_experiment(self, experiment: Path, configs: list[dict[str, Any]]) -> None:
        saved = experiment / PLAN_FILE
        if self.options.resume:
            if not saved.is_file():
                raise ConfigError("resume", "", f"{experiment.parent} holds no Ray sweep to go on")
            if json.loads(saved.read_text()) != json.loads(json.dumps(configs)):
                raise ConfigError(
                    "resume",
                    "",
                    f"the sweep in {experiment.parent} was started with other encodings, "
                    "seeds, grid or settings; give the same ones to go on",
                )
        elif experiment.exists():
            shutil.rmtree(experiment)  # the CLI refused this without --force

    def _tuner(
        self,
        tune: Any,
        trainable: Any,
        plan: SweepPlan,
        configs: list[dict[str, Any]],
        out: Path,
        echo: bool,
    ) -> Any:
        from ray.tune import CheckpointConfig, FailureConfig, RunConfig, TuneConfig

        scheduler = None
        if self.options.scheduler == "asha":
            from ray.tune.schedulers import ASHAScheduler

            final = math.ceil(plan.steps / plan.rollout_steps) * plan.rollout_steps
            grace = self.options.asha_grace_steps or max(plan.rollout_steps, plan.steps // 4)
            if grace >= final:
                raise ConfigError(
                    "asha_grace_steps", str(grace), f"expected fewer steps than a trial's ({final})"
                )
            # Rungs below the last rollout only, and no stop at max_t: a trial that got to
            # its end always reports its policy.
            scheduler = ASHAScheduler(
                time_attr="steps",
                metric="mean_return",
                mode="max",
                max_t=final - 1,
                grace_period=grace,
                reduction_factor=ASHA_REDUCTION,
                stop_last_trials=False,
            )
        return tune.Tuner(
            trainable,
            param_space={"trial": tune.grid_search(configs)},
            tune_config=TuneConfig(
                scheduler=scheduler,
                max_concurrent_trials=self.options.max_concurrent_trials,
                reuse_actors=True,
                trial_name_creator=trial_name,
                trial_dirname_creator=trial_dirname,
            ),
            run_config=RunConfig(
                name=EXPERIMENT,
                storage_path=str(out.resolve()),
                failure_config=FailureConfig(max_failures=self.options.retries),
                checkpoint_config=CheckpointConfig(num_to_keep=1),
                callbacks=[_progress_callback(plan.steps, echo)],
                verbose=0,
            ),
        )

    def _land(self, grid: Any, trials: list[Trial], out: Path) -> list[TrialOutcome]:
        by_name = {str(r.config["trial"]["name"]): r for r in grid}
        failed = [t.name for t in trials if by_name[t.name].error is not None]
        if failed:
            raise SweepError(
                failed,
                f"{len(failed)} trial(s) failed on every try ({', '.join(failed)}); "
                f"their errors are under {out / EXPERIMENT}; resuming the sweep runs them again",
            )
        outcomes = []
        for trial in trials:
            result = by_name[trial.name]
            folder = out / trial.name
            if result.metrics.get("finished") and result.checkpoint is not None:
                result.checkpoint.to_directory(str(folder))
                outcomes.append(TrialOutcome(trial, _landed(folder)))
            else:  # stopped by the scheduler: the curve it reported up to there
                curve = _last_attempt(result.metrics_dataframe.to_dict("records"))
                outcomes.append(TrialOutcome(trial, _stopped(folder, curve), stopped_early=True))
        return outcomes


def _unfinished(tune: Any, experiment: Path) -> list[str]:
    """The trials the saved experiment has yet to run or finish (what ``--resume`` would run):
    Tune's saved state, not the ended run's trials, which it marks terminated on Ctrl-C."""
    analysis = tune.ExperimentAnalysis(str(experiment))
    done = ("TERMINATED", "ERROR")
    return [trial_name(t) for t in analysis.trials if t.status not in done]


def _check_cpus(ray: Any, cpus: float) -> None:
    most = max((n["Resources"].get("CPU", 0.0) for n in ray.nodes() if n["Alive"]), default=0)
    if cpus > most:
        raise ConfigError(
            "cpus_per_trial",
            f"{cpus:g}",
            f"no node of the cluster has that many CPUs (the most is {most:g}): ask fewer, "
            "or train on dummy envs or fewer of them",
        )


def _landed(folder: Path) -> TrainResult:
    """A trial's TrainResult read back from its landed policy folder."""
    meta = read_settings(folder)[2]
    cpu = meta.get("cpu_s")
    return TrainResult(
        read_curve(folder / CURVE_FILE),
        float(meta["wall_s"]),
        int(meta["steps"]),
        folder,
        math.nan if cpu is None else float(cpu),
        bool(meta["interrupted"]),
    )


def _last_attempt(rows: list[dict[str, Any]]) -> list[CurvePoint]:
    """The curve points of a trial's last try (a retried trial's steps start again)."""
    points: list[CurvePoint] = []
    for row in rows:
        if "steps" not in row or not isinstance(row["steps"], int | float):
            continue
        if points and row["steps"] <= points[-1].steps:
            points = []
        if not row.get("finished"):
            # Tune's table gives numpy numbers; the curve holds Python ones, as a local run's
            fields: dict[str, Any] = {name: float(row[name]) for name in CURVE_FIELDS}
            fields["steps"], fields["episodes"] = int(row["steps"]), int(row["episodes"])
            points.append(CurvePoint(**fields))
    return points


def _stopped(folder: Path, curve: list[CurvePoint]) -> TrainResult:
    """A stopped trial's curve written to ``folder`` as a local run's, as its TrainResult."""
    folder.mkdir(parents=True, exist_ok=True)
    with (folder / CURVE_FILE).open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(CURVE_FIELDS)
        writer.writerows([getattr(p, name) for name in CURVE_FIELDS] for p in curve)
    steps = curve[-1].steps if curve else 0
    wall = curve[-1].wall_s if curve else 0.0
    return TrainResult(curve, wall, int(steps), folder)


def _progress_callback(total: int, echo: bool) -> Any:
    """A Tune callback printing each trial's rollouts, failures and ends to stderr (nothing
    when ``echo`` is False); it holds no stream, so Tune can save it with the experiment."""
    from ray.tune import Callback

    class Progress(Callback):  # type: ignore[misc]
        def on_trial_result(
            self, iteration: int, trials: Any, trial: Any, result: Any, **info: Any
        ) -> None:
            if echo and not result.get("finished"):
                ret = result.get("mean_return", math.nan)
                sys.stderr.write(
                    f"  {trial_name(trial)}: {int(result.get('steps', 0)):>9d}/{total} steps  "
                    f"return {'n/a' if math.isnan(ret) else format(ret, '.2f')}\n"
                )

        def on_trial_recover(self, iteration: int, trials: Any, trial: Any, **info: Any) -> None:
            if echo:
                sys.stderr.write(
                    f"  {trial_name(trial)}: failed, running it again from the start\n"
                )

        def on_trial_error(self, iteration: int, trials: Any, trial: Any, **info: Any) -> None:
            if echo:
                sys.stderr.write(f"  {trial_name(trial)}: failed ({trial.error_file})\n")

        def on_trial_complete(self, iteration: int, trials: Any, trial: Any, **info: Any) -> None:
            if echo:
                finished = trial.last_result.get("finished")
                sys.stderr.write(
                    f"  {trial_name(trial)}: {'done' if finished else 'stopped early'}\n"
                )

    return Progress()
