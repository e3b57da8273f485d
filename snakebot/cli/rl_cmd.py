"""``snakebot rl train|eval|compare``: learn gaits in the twin's Gymnasium environments.

Nothing here imports gymnasium, torch or stable-baselines3 until a subcommand runs; a missing
one is reported with the extra that installs it (``snakebot[rl]``, ``snakebot[rl-train]``).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from snakebot.cli.common import (
    add_dry_run,
    add_force_option,
    positive_int,
    print_json,
    refuse_replacing,
    refuse_replacing_in,
    report_dry_run,
    robot_arg,
)
from snakebot.errors import ConfigError, UsageError

ENV_CHOICES = ("snakebot/SnakeGoal-v0", "snakebot/SnakeVelocity-v0")
ENCODING_CHOICES = ("simple", "sinusoid", "dft", "dft_shift", "compound")
# snakebot.rl.tasks.GOAL_TASKS, named here so that building the parser imports no gymnasium.
TASK_CHOICES = ("near", "seed")
# PPO throughput measured on two cores with tools/bench_rl.py (docs/learning.md, "Which
# vectorisation"): the fastest setting is the default.
DEFAULT_N_ENVS = 2
DEFAULT_VEC = "subproc"
DEFAULT_ENV = {"env": ENV_CHOICES[0], "encoding": "dft_shift", "robot": "snake8"}
DEFAULT_ROLLOUT = 2048


def add_parser(subparsers: Any) -> None:
    """Register ``rl`` and its subcommands."""
    parser = subparsers.add_parser(
        "rl",
        help="train and evaluate learned gaits (needs snakebot[rl-train])",
        description="Reinforcement learning on the twin: Gymnasium environments "
        "snakebot/SnakeGoal-v0 and snakebot/SnakeVelocity-v0, trained with PPO.",
    )
    sub = parser.add_subparsers(dest="rl_command", metavar="SUBCOMMAND", required=True)

    train = sub.add_parser("train", help="train a policy; saves it with its env settings")
    _env_options(train)
    train.add_argument("--algo", choices=("ppo",), default="ppo", help="algorithm (ppo)")
    train.add_argument(
        "--steps", type=positive_int, default=200_000, help="env steps to train (default 200000)"
    )
    _vec_options(train)
    train.add_argument(
        "--rollout",
        type=positive_int,
        help="env steps per PPO update, over all envs (default 2048; with "
        "--resume: the saved policy's)",
    )
    train.add_argument(
        "--ppo",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="PPO setting (repeatable), e.g. --ppo learning_rate=1e-4: "
        "learning_rate, batch_size, n_epochs, gamma, gae_lambda, clip_range, "
        "ent_coef, vf_coef, max_grad_norm (default SB3's; with --resume: the "
        "saved policy's)",
    )
    train.add_argument(
        "--resume",
        type=Path,
        metavar="DIR",
        help="go on training the policy in DIR (its env and PPO settings) for "
        "--steps more steps; writes into DIR unless --out names another folder",
    )
    train.add_argument(
        "--checkpoints",
        type=int,
        default=10,
        metavar="N",
        help="actor snapshots kept in OUT/checkpoints, evenly spaced over the run, for "
        "`rl curve` (default 10; 0: none)",
    )
    train.add_argument("--out", type=Path, help="policy folder (default rl-runs/ENV-ENCODING)")
    train.add_argument("--json", action="store_true", help="print the summary as JSON")
    add_force_option(train)
    add_dry_run(train, "no training, no policy folder")
    train.set_defaults(handler=run_train, writes=True)

    evaluate = sub.add_parser("eval", help="evaluate a trained policy (and zero/random ones)")
    evaluate.add_argument(
        "policy",
        type=Path,
        nargs="+",
        help="policy folder from `rl train`; several: training seeds of one configuration "
        "(rl compare --seeds writes OUT/ENCODING/seed-S), shown as one row with 95%% "
        "intervals over them",
    )
    evaluate.add_argument(
        "--episodes",
        type=positive_int,
        default=20,
        help="episodes, on seeds SEED..SEED+N-1 (default 20)",
    )
    evaluate.add_argument("--seed", type=int, default=1000, help="first episode seed")
    evaluate.add_argument(
        "--baselines",
        choices=("on", "off"),
        default="on",
        help="also run a zero and a random policy on the same seeds and, for a goal policy, "
        "two serpenoids steered toward the goal (bearing, steered: docs/learning.md)",
    )
    evaluate.add_argument("--video", type=Path, help="render the first episode to an MP4")
    evaluate.add_argument("--json", action="store_true", help="print the results as JSON")
    add_force_option(evaluate)
    add_dry_run(evaluate, "no episodes, no video")
    evaluate.set_defaults(handler=run_eval, writes=True)  # --video

    curve = sub.add_parser(
        "curve",
        help="learning curve from deterministic evaluations of a policy's saved checkpoints",
    )
    curve.add_argument(
        "policy",
        type=Path,
        nargs="+",
        help="policy folder(s) from `rl train`; several: training seeds of one configuration, "
        "averaged with 95%% intervals",
    )
    curve.add_argument(
        "--episodes",
        type=positive_int,
        default=10,
        help="episodes per checkpoint, on seeds SEED..SEED+N-1 (default 10)",
    )
    curve.add_argument("--seed", type=int, default=1000, help="first episode seed")
    curve.add_argument("--json", action="store_true", help="print the curve as JSON")
    add_force_option(curve)
    add_dry_run(curve, "no episodes, no eval_curve files")
    curve.set_defaults(handler=run_curve, writes=True)

    compare = sub.add_parser("compare", help="train every encoding, plot the curves together")
    compare.add_argument("--env", choices=ENV_CHOICES, default=ENV_CHOICES[0])
    compare.add_argument(
        "--encodings",
        default="simple,sinusoid,dft,dft_shift",
        help="comma-separated encodings (default the seed's four)",
    )
    compare.add_argument(
        "--robot", default="snake8", type=robot_arg, help="robot name or file (default snake8)"
    )
    compare.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="env setting for every run (repeatable)",
    )
    _task_option(compare)
    compare.add_argument(
        "--steps",
        type=positive_int,
        default=100_000,
        help="env steps per encoding (default 100000)",
    )
    compare.add_argument("--seed", type=int, default=0, help="first seed (default 0)")
    compare.add_argument(
        "--seeds",
        type=positive_int,
        default=1,
        help="train each encoding on seeds SEED..SEED+N-1 (default 1: OUT/ENCODING; more: "
        "OUT/ENCODING/seed-S)",
    )
    compare.add_argument(
        "--grid",
        action="append",
        default=[],
        metavar="KEY=V1,V2,...",
        help="also sweep a PPO or scalar env setting over these values (repeatable: every "
        "combination; each trial in OUT/ENCODING/KEY=V,.../)",
    )
    compare.add_argument(
        "--ppo",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="PPO setting for every run (repeatable), as rl train's",
    )
    compare.add_argument(
        "--rollout",
        type=positive_int,
        default=DEFAULT_ROLLOUT,
        help=f"env steps per PPO update, over all envs (default {DEFAULT_ROLLOUT})",
    )
    _vec_options(compare)
    _executor_options(compare)
    compare.add_argument(
        "--out",
        type=Path,
        default=Path("rl-runs/compare"),
        help="folder: one policy folder per encoding and compare.png",
    )
    compare.add_argument("--json", action="store_true", help="print the results as JSON")
    add_force_option(compare)
    add_dry_run(compare, "no training, no policy folders, no plot")
    compare.set_defaults(handler=run_compare, writes=True)


def _env_options(parser: argparse.ArgumentParser) -> None:
    # No argparse defaults: --resume takes all three from the saved policy (run_train fills in
    # DEFAULT_ENV otherwise), and one given with it is refused rather than ignored.
    parser.add_argument(
        "--env", choices=ENV_CHOICES, help="environment (default snakebot/SnakeGoal-v0)"
    )
    parser.add_argument(
        "--encoding", choices=ENCODING_CHOICES, help="action encoding (default dft_shift)"
    )
    parser.add_argument("--robot", type=robot_arg, help="robot name or file (default snake8)")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="env setting (repeatable), e.g. --set episode_s=20 "
        "--set goal_distance_bl=2,3; see docs/learning.md",
    )
    parser.add_argument("--seed", type=int, default=0, help="training seed (default 0)")
    _task_option(parser)


def _task_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--task",
        choices=TASK_CHOICES,
        help="goal-task preset: near (goals 2-4 body lengths from the COM, 30 s episodes) or "
        "seed (the seed's task: goals 5-7 m from the head, -1 a step, +100 at the goal, 200 s "
        "episodes, gamma 0.999); default near; --set and --ppo override it (docs/learning.md)",
    )


def _executor_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("Ray (the 'cluster' extra; docs/learning.md)")
    group.add_argument(
        "--executor",
        choices=("local", "ray"),
        default="local",
        help="local: one trial after the other here; ray: Ray Tune trials (default local)",
    )
    group.add_argument(
        "--address", help="Ray cluster HOST:PORT (default: a local one on 127.0.0.1)"
    )
    group.add_argument(
        "--scheduler",
        choices=("none", "asha"),
        default="none",
        help="asha: stop trials whose return falls into the worse half at a rung",
    )
    group.add_argument(
        "--asha-grace",
        dest="asha_grace_steps",
        type=positive_int,
        metavar="STEPS",
        help="first ASHA rung, env steps (default a quarter of --steps, one rollout at least)",
    )
    group.add_argument(
        "--cpus-per-trial",
        type=float,
        help="CPUs Ray reserves per trial (default --n-envs for subproc envs, 1 for dummy)",
    )
    group.add_argument(
        "--max-concurrent-trials", type=positive_int, help="at most this many trials at once"
    )
    group.add_argument(
        "--ray-cpus",
        dest="num_cpus",
        type=positive_int,
        help="CPUs of the local Ray cluster started without --address (default all)",
    )
    group.add_argument(
        "--retries",
        type=int,
        default=2,
        help="runs again a trial that failed (a lost node) this often (default 2)",
    )
    group.add_argument(
        "--resume",
        action="store_true",
        help="go on with the interrupted Ray sweep in --out (finished trials are kept)",
    )


RAY_ONLY = {  # dest -> flag of the options only --executor ray takes
    "address": "--address",
    "scheduler": "--scheduler",
    "asha_grace_steps": "--asha-grace",
    "cpus_per_trial": "--cpus-per-trial",
    "max_concurrent_trials": "--max-concurrent-trials",
    "num_cpus": "--ray-cpus",
    "resume": "--resume",
}


def _ray_executor(args: argparse.Namespace) -> Any:
    """The Ray executor of ``rl compare --executor ray``; None for a local run, where each
    Ray option is a usage error."""
    defaults = {"scheduler": "none", "resume": False}
    given = [
        flag
        for key, flag in RAY_ONLY.items()
        if getattr(args, key) not in (None, defaults.get(key))
    ]
    if args.executor == "local":
        if given or args.retries != 2:
            raise UsageError(f"{', '.join(given) or '--retries'}: needs --executor ray")
        return None
    from snakebot.rl.compare_ray import RayExecutor, RayOptions, require_tune

    options = RayOptions(  # checked first: a usage error needs no Ray to be told
        address=args.address,
        num_cpus=args.num_cpus,
        scheduler=args.scheduler,
        asha_grace_steps=args.asha_grace_steps,
        cpus_per_trial=args.cpus_per_trial,
        max_concurrent_trials=args.max_concurrent_trials,
        retries=args.retries,
        resume=args.resume,
    )
    require_tune()
    return RayExecutor(options)


def parse_grid(items: list[str]) -> dict[str, tuple[Any, ...]]:
    """--grid KEY=V1,V2,...: each key's values (numbers or words); ConfigError naming the item
    for one without values or a key given twice."""
    grid: dict[str, tuple[Any, ...]] = {}
    for item in items:
        key, sep, raw = item.partition("=")
        key = key.strip()
        if not sep or not key or not raw.strip():
            raise ConfigError(
                "--grid", item, "expected KEY=V1,V2,..., e.g. learning_rate=3e-4,1e-4"
            )
        if key in grid:
            raise ConfigError("--grid", item, f"{key} is given twice")
        values: list[Any] = []
        for part in (p.strip() for p in raw.split(",")):
            try:
                values.append(_number(part))
            except ValueError:
                values.append(part)
        grid[key] = tuple(values)
    return grid


def _vec_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--n-envs",
        type=positive_int,
        default=DEFAULT_N_ENVS,
        help=f"parallel envs (default {DEFAULT_N_ENVS}, measured fastest on two cores)",
    )
    parser.add_argument(
        "--vec",
        choices=("dummy", "subproc"),
        default=DEFAULT_VEC,
        help=f"dummy: envs in this process; subproc: one process each (default {DEFAULT_VEC})",
    )


def parse_settings(items: list[str]) -> dict[str, Any]:
    """--set KEY=VALUE: numbers, comma lists of numbers (tuples) or words."""
    out: dict[str, Any] = {}
    for item in items:
        key, sep, raw = item.partition("=")
        if not sep or not key.strip():
            raise ConfigError("--set", item, "expected KEY=VALUE, e.g. episode_s=20")
        parts = [p.strip() for p in raw.split(",")]
        try:
            values: list[Any] = [_number(p) for p in parts]
        except ValueError:
            if len(parts) > 1:
                raise ConfigError("--set", item, "expected numbers in a comma list") from None
            values = [raw.strip()]
        out[key.strip()] = tuple(values) if len(values) > 1 else values[0]
    return out


def _number(text: str) -> float | int:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(text)
    return int(value) if text.lstrip("+-").isdigit() else value


def env_kwargs(args: argparse.Namespace, encoding: str) -> dict[str, Any]:
    """The kwargs of gymnasium.make: robot, encoding and --set, checked by building them, with
    every default filled in (a policy keeps the settings it was trained with, whatever later
    versions change)."""
    given = parse_settings(args.set)
    for key in ("robot", "encoding"):
        if key in given:
            raise UsageError(f"--set {key}=...: use --{key}")
    _check_robot(args.robot)
    from snakebot.rl.settings import GoalSettings, VelocitySettings, settings_dict, split_kwargs

    task = GoalSettings if "Goal" in args.env else VelocitySettings
    preset = task_preset(args)
    kwargs = {"robot": args.robot, "encoding": encoding, **preset.env, **given}
    return settings_dict(*split_kwargs(kwargs, task))


def task_preset(args: argparse.Namespace) -> Any:
    """The GoalTask of ``--task`` (near without one); UsageError for --task with the velocity
    environment, which has no goals."""
    if args.task is not None and "Goal" not in args.env:
        raise UsageError(f"--task {args.task}: the goal task's presets need --env {ENV_CHOICES[0]}")
    from snakebot.rl.tasks import goal_task

    return goal_task(args.task or "near")


def _check_robot(name: str) -> None:
    """ConfigError now (before any env starts) for a robot that cannot be loaded, or a
    mass-spring body: the environments drive servo snakes."""
    from snakebot.config import RobotConfig
    from snakebot.session import load_robot

    if not isinstance(load_robot(name), RobotConfig):
        raise ConfigError(
            "--robot",
            name,
            "the learning environments drive servo snakes (robot files), not mass-spring bodies",
        )


def _check_out(out: Path) -> None:
    """OutputError for an output folder that is a file (a dry run creates nothing)."""
    from snakebot.errors import OutputError

    for folder in (out, *out.parents):
        if folder.exists() and not folder.is_dir():
            raise OutputError(folder, "is a file, not a folder: cannot write the policy there")


def parse_ppo(items: list[str]) -> dict[str, Any]:
    """--ppo KEY=VALUE as PPO settings, each checked (ConfigError naming --ppo and the item)."""
    from snakebot.rl.resume import check_ppo

    values = parse_settings(items)
    for item in items:
        key = item.partition("=")[0].strip()
        try:
            check_ppo({key: values[key]}, "--ppo")
        except ConfigError as exc:
            raise ConfigError("--ppo", item, exc.reason) from None
    return values


def _train_plan(args: argparse.Namespace) -> tuple[Any, Path, bool]:
    """The TrainSettings of ``rl train`` and its output folder (and whether it is the resumed
    policy's own); every check done, nothing written."""
    from snakebot.rl.policy_file import TRAIN_FILES
    from snakebot.rl.resume import resume_point
    from snakebot.rl.train import TrainSettings

    ppo = parse_ppo(args.ppo)
    resume = None
    if args.resume is not None:
        given = [f"--{key}" for key in (*DEFAULT_ENV, "task") if getattr(args, key) is not None]
        given += ["--set"] if args.set else []
        if given:
            raise UsageError(
                f"--resume trains on in the saved policy's environment: drop "
                f"{', '.join(given)} (or train a new policy without --resume)"
            )
        resume = resume_point(args.resume)
        _check_robot(resume.env_kwargs["robot"])
        env_id, kwargs = resume.env_id, resume.env_kwargs
        ppo = {**resume.ppo, **ppo}
        rollout = args.rollout or resume.rollout_steps
        out = args.out or args.resume
    else:
        for key, default in DEFAULT_ENV.items():
            setattr(args, key, getattr(args, key) or default)
        env_id, kwargs = args.env, env_kwargs(args, args.encoding)
        ppo = {**task_preset(args).ppo, **ppo}
        rollout = args.rollout or DEFAULT_ROLLOUT
        out = args.out or Path("rl-runs") / f"{args.env.split('/')[-1]}-{args.encoding}"
    _check_out(out)
    in_place = resume is not None and out.resolve() == resume.folder.resolve()
    if not in_place:  # resuming in place is what --resume asks for
        refuse_replacing_in(out, TRAIN_FILES, "trained policy", force=args.force)
    settings = TrainSettings(
        env_id,
        kwargs,
        args.steps,
        seed=args.seed,
        n_envs=args.n_envs,
        vec=args.vec,
        algo=args.algo,
        rollout_steps=rollout,
        ppo=ppo,
        resume=resume,
        checkpoints=args.checkpoints,
    )
    return settings, out, in_place


def run_train(args: argparse.Namespace) -> int:
    """Train one policy (or go on training a saved one), print where it went."""
    from snakebot.rl.train import dump_json, train

    settings, out, in_place = _train_plan(args)
    resume = settings.resume
    kwargs = settings.env_kwargs
    if args.dry_run:
        plan = {
            "env": settings.env_id,
            "encoding": kwargs["encoding"],
            "robot": kwargs["robot"],
            "steps": args.steps,
            "out": str(out),
            "env_kwargs": kwargs,
            "ppo": settings.ppo,
            "rollout": settings.rollout_steps,
        }
        if resume is not None:
            plan["resume"] = {"folder": str(resume.folder), "steps": resume.steps}
        return report_dry_run(args, plan)
    if not args.json:
        what = f"{settings.env_id} ({kwargs['encoding']}, {kwargs['robot']})"
        if resume is not None:
            where = "in place" if in_place else f"-> {out}"
            print(
                f"resuming {what} from {resume.steps} steps in {resume.folder} for "
                f"{args.steps} more on {args.n_envs} {args.vec} env(s) {where}"
            )
        else:
            print(
                f"training {what} for {args.steps} steps on {args.n_envs} {args.vec} "
                f"env(s) -> {out}"
            )
    result = train(settings, out)
    summary = dump_json(result)
    if args.json:
        print_json(summary)
    else:
        ended = "interrupted after" if result.interrupted else "done:"
        cpu = "" if summary["cpu_s"] is None else f", {summary['cpu_s']:.0f} CPU s"
        print(
            f"{ended} {summary['steps']} steps in {summary['wall_s']:.0f} s "
            f"({summary['steps_per_s']:.0f} steps/s{cpu}); "
            f"policy, learning_curve.csv and .png in {out}"
        )
    return 130 if result.interrupted else 0


def run_eval(args: argparse.Namespace) -> int:
    """Evaluate a policy folder against the baselines (zero, random, steered serpenoids) on the
    same seeds."""
    from snakebot.rl.evaluate import evaluate_folder, print_table

    if args.video is not None:
        refuse_replacing(args.video, "video", force=args.force)
    if args.dry_run:
        from snakebot.rl.evaluate import load_policies

        policy = load_policies(args.policy)[0]
        if args.video is not None:
            _check_out(args.video.parent)
        return report_dry_run(
            args,
            {
                "policy": [str(folder) for folder in args.policy],
                "env": policy.env_id,
                "episodes": args.episodes,
                "seed": args.seed,
                "video": None if args.video is None else str(args.video),
            },
        )
    results = evaluate_folder(
        args.policy,
        episodes=args.episodes,
        seed=args.seed,
        baselines=args.baselines == "on",
        video=args.video,
    )
    if args.json:
        print_json({name: r.summary() for name, r in results.items()})
    else:
        print_table(results)
    return 0


def run_curve(args: argparse.Namespace) -> int:
    """Evaluate every saved checkpoint of each folder; eval_curve.csv and .png into each."""
    from snakebot.rl.curve import (
        EVAL_CURVE_FILE,
        EVAL_CURVE_PLOT,
        across_seeds,
        checkpoints,
        evaluate_checkpoints,
        print_curve,
        write_curve,
    )
    from snakebot.rl.evaluate import load_policies

    load_policies(args.policy)  # one configuration, every folder readable: checked first
    for folder in args.policy:
        checkpoints(folder)
        _check_out(folder)
        names = (EVAL_CURVE_FILE, EVAL_CURVE_PLOT)
        refuse_replacing_in(folder, names, "evaluation curve", force=args.force)
    if args.dry_run:
        return report_dry_run(
            args,
            {
                "policy": [str(folder) for folder in args.policy],
                "checkpoints": {str(f): [s for s, _ in checkpoints(f)] for f in args.policy},
                "episodes": args.episodes,
                "seed": args.seed,
            },
        )
    curves = {}
    for folder in args.policy:
        curves[folder] = evaluate_checkpoints(folder, episodes=args.episodes, seed=args.seed)
        write_curve(folder, curves[folder])
    rows = across_seeds(curves)
    if args.json:
        print_json({"curve": rows, "folders": [str(folder) for folder in args.policy]})
    else:
        print_curve(rows)
        print(f"{EVAL_CURVE_FILE} and {EVAL_CURVE_PLOT} in each policy folder")
    return 0


def run_compare(args: argparse.Namespace) -> int:
    """Train each encoding in turn; curves side by side in compare.png."""
    encodings = [e.strip() for e in args.encodings.split(",") if e.strip()]
    bad = [e for e in encodings if e not in ENCODING_CHOICES]
    if bad or not encodings:
        raise ConfigError(
            "--encodings", args.encodings, f"expected a comma list of {', '.join(ENCODING_CHOICES)}"
        )
    from snakebot.rl.compare import compare
    from snakebot.rl.sweep import SweepPlan, comparison_table

    runs = {e: env_kwargs(args, e) for e in encodings}
    ppo, grid = {**task_preset(args).ppo, **parse_ppo(args.ppo)}, parse_grid(args.grid)
    executor = _ray_executor(args)
    seeds = tuple(range(args.seed, args.seed + args.seeds))
    plan = SweepPlan(
        args.env, runs, args.steps, seeds, grid, args.n_envs, args.vec, args.rollout, ppo
    )
    _check_out(args.out)
    from snakebot.rl.policy_file import TRAIN_FILES

    if not args.resume:  # a resumed sweep goes on in its own folder
        from snakebot.rl.compare_ray import EXPERIMENT

        names = ("compare.png", "compare.json", EXPERIMENT)
        refuse_replacing_in(args.out, names, "comparison", force=args.force)
        for trial in plan.trials():
            folder = args.out / trial.name
            refuse_replacing_in(folder, TRAIN_FILES, "trained policy", force=args.force)
    if args.dry_run:
        return report_dry_run(
            args,
            {
                "env": args.env,
                "encodings": encodings,
                "robot": args.robot,
                "steps": args.steps,
                "out": str(args.out),
                "executor": args.executor,
                "env_kwargs": runs,
                "ppo": ppo,
                "trials": [t.name for t in plan.trials()],
            },
        )
    summary = compare(
        args.env,
        runs,
        args.steps,
        args.out,
        seed=args.seed,
        n_envs=args.n_envs,
        vec=args.vec,
        seeds=args.seeds,
        grid=grid,
        rollout_steps=args.rollout,
        ppo=ppo,
        executor=executor,
    )
    if args.json:
        print_json(summary)
    else:
        print(comparison_table(summary["table"]), end="")
        print(f"compare.png and one policy folder per trial in {args.out}")
    return 0
