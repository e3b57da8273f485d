"""``snakebot tune gait|gains``: search gait parameters on the twin, or servo gains on a backend."""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from snakebot.cli.backend_options import (
    add_backend_argument,
    add_option_flags,
    backend_spec,
    flag_errors,
    given_options,
)
from snakebot.cli.common import (
    RATE_HZ,
    add_force_option,
    add_robot_option,
    add_write_back_options,
    bounded_float,
    check_folder,
    check_robot_copy,
    check_writable,
    copy_for_write,
    finite_float,
    gait_arg,
    not_written_note,
    positive_float,
    positive_int,
    print_json,
    robot_name,
    robot_write_target,
    write_report,
)
from snakebot.cli.terrain_options import add_terrain_options, refuse_friction_model, twin_ground
from snakebot.config import RobotConfig, load_robot
from snakebot.config.body import BodyConfig
from snakebot.config.body_loader import load_robot_or_body
from snakebot.errors import ConfigError, SafetyLimitError, UsageError
from snakebot.gaits import get_spec, parse_set_options

if TYPE_CHECKING:
    from snakebot.backends.twin import GroundFriction


def add_parser(subparsers: Any) -> None:
    """Register ``tune`` and its two subcommands."""
    parser = subparsers.add_parser("tune", help="tune gait parameters or servo gains")
    commands = parser.add_subparsers(dest="tune_command", metavar="WHAT", required=True)
    _add_gait_parser(commands)
    _add_gains_parser(commands)
    parser.set_defaults(handler=run)


def _add_gait_parser(commands: Any) -> None:
    from snakebot.tuning.objectives import OBJECTIVES
    from snakebot.tuning.problem import ENGINES
    from snakebot.tuning.tuner import DEFAULT_BUDGET, METHODS

    parser = commands.add_parser(
        "gait",
        help="search a gait's parameters on the twin for speed, efficiency or a heading",
        description="Each candidate runs like `snakebot run --duration D --rate R` on the twin; "
        "candidates that break joint limits, exceed the servo's speed or torque, or leave the "
        "ground are penalised so the best gait is playable on the robot.",
    )
    add_robot_option(parser)
    parser.add_argument(
        "--gait", type=gait_arg, default="serpenoid", help="gait to tune (default serpenoid)"
    )
    parser.add_argument(
        "--set", action="append", default=[], metavar="KEY=VALUE", help="fix a gait parameter"
    )
    parser.add_argument(
        "--params",
        help="comma-separated parameters to search; a+b ties two "
        "(default: the gait's default search, see `snakebot gaits`)",
    )
    parser.add_argument(
        "--bounds",
        action="append",
        default=[],
        metavar="NAME=LOW:HIGH",
        help="search bounds, e.g. omega=0.5:4*pi (repeatable or comma-separated)",
    )
    parser.add_argument("--objective", choices=OBJECTIVES, default="speed")
    parser.add_argument(
        "--heading",
        type=finite_float,
        default=0.0,
        metavar="DEG",
        help="world direction for speed_toward_heading (0 = +x, the head's start direction)",
    )
    parser.add_argument("--method", choices=METHODS, default="cmaes")
    parser.add_argument(
        "--budget",
        type=positive_int,
        help="most evaluations (default: "
        + ", ".join(f"{m} {n}" for m, n in DEFAULT_BUDGET.items())
        + ")",
    )
    parser.add_argument(
        "--workers",
        type=positive_int,
        default=min(2, os.cpu_count() or 1),
        help="parallel simulations (default: 2, or 1 on a 1-core machine)",
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument(
        "--duration",
        type=positive_float,
        default=10.0,
        help="seconds per evaluation, as `snakebot run --duration` (default 10)",
    )
    parser.add_argument("--rate", type=RATE_HZ, default=100.0, help="control rate in Hz")
    parser.add_argument("--friction", metavar="AXIAL,LATERAL", help="override the ground model")
    add_terrain_options(parser)
    parser.add_argument(
        "--engine",
        choices=ENGINES,
        default="batch",
        help="batch: mujoco.batch threads (default); processes: a process pool; warp: every "
        "candidate a world of one MuJoCo Warp model (the gpu extra; docs/tuning.md)",
    )
    parser.add_argument(
        "--device",
        default="cpu",
        metavar="DEVICE",
        help="Warp device for --engine warp: cpu (default), cuda or cuda:N",
    )
    _add_executor_options(parser)
    parser.add_argument(
        "--allow-roll",
        action="store_true",
        help="do not stop runs whose head turns upside down (automatic for gaits that roll over)",
    )
    parser.add_argument("--out", type=Path, help="write the best gait to this gait file (TOML)")
    parser.add_argument("--report", type=Path, metavar="DIR", help="write plots and summary.json")
    add_force_option(parser)
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument("--quiet", action="store_true", help="no progress bar on stderr")
    parser.add_argument(
        "--dry-run", action="store_true", help="tune and report, but write no --out or --report"
    )
    parser.set_defaults(writes=True)


def run(args: argparse.Namespace) -> int:
    """Dispatch to the chosen subcommand."""
    if args.tune_command == "gains":
        return run_gains(args)
    return run_gait(args)


def run_gait(args: argparse.Namespace) -> int:
    """Tune, then write the gait file, the report and the summary."""
    from snakebot.tuning.objectives import objective_for
    from snakebot.tuning.problem import EvalPlan
    from snakebot.tuning.progress import ProgressBar, gait_summary_text
    from snakebot.tuning.space import build_space, parse_bounds, tuning_base
    from snakebot.tuning.tuner import DEFAULT_BUDGET, save_best_gait, tune_gait

    robot = load_robot_or_body(robot_name(args, hardware=False, what="tune gait"))
    _check_outputs(args, robot)
    fixed = parse_set_options(args.gait, args.set)
    base = tuning_base(args.gait, robot.joint_count, fixed)
    names = [p.strip() for p in args.params.split(",")] if args.params else None
    limit = float(min(-robot.lower_rad.max(), robot.upper_rad.min()))
    space = build_space(args.gait, base, names, parse_bounds(args.bounds), limit)
    if args.method == "cmaes":
        from snakebot.tuning.cmaes import require_cma

        require_cma()  # fail before any simulation when the package is missing
    if args.report is not None:
        from snakebot.tuning.plots import pyplot

        pyplot()
    budget = args.budget if args.budget is not None else DEFAULT_BUDGET[args.method]
    plan = EvalPlan(
        duration_s=args.duration,
        rate_hz=args.rate,
        workers=max(1, args.workers),
        engine=args.engine,
        device=_warp_device(args),
        allow_roll=args.allow_roll or get_spec(args.gait).rolls_over,
        friction=_friction(robot, args.friction),
        **_twin_ground(robot, args),
        **_executor(robot, args),
    )
    objective = objective_for(args.objective, args.heading, robot.body_length_m)
    bar = None if args.quiet else ProgressBar(budget)
    result = tune_gait(
        robot,
        space,
        objective,
        args.method,
        budget=budget,
        seed=args.seed,
        plan=plan,
        listener=bar,
    )
    if bar is not None:
        bar.finish()
    summary = result.summary()
    if args.dry_run:
        summary["not_written"] = "dry run: no gait file or report written"
    elif args.out is not None and result.best.feasible:
        save_best_gait(result, args.out)
        summary["gait_file"] = str(args.out)
    if args.report is not None and not args.dry_run:
        from snakebot.tuning.plots import gait_plots

        write_report(args.report, summary, lambda directory: gait_plots(result, directory))
    if args.json:
        print_json(summary)
    else:
        print(gait_summary_text(summary))
    if not result.best.feasible:
        raise SafetyLimitError(
            "no candidate stayed inside the servo envelope (joint limits, speed, torque, ground "
            "contact); narrow --bounds or raise --budget. Nothing was written to --out"
        )
    return 0


def _warp_device(args: argparse.Namespace) -> str:
    """--device, which only --engine warp reads."""
    if args.device != "cpu" and args.engine != "warp":
        raise UsageError(f"--device {args.device}: only --engine warp runs on a Warp device")
    return str(args.device)


def _add_executor_options(parser: argparse.ArgumentParser) -> None:
    from snakebot.tuning.problem import EXECUTORS

    parser.add_argument(
        "--executor",
        choices=EXECUTORS,
        default="local",
        help="local: this machine (default); ray: Ray actors, one per node (docs/cluster.md)",
    )
    parser.add_argument(
        "--address",
        metavar="HOST:PORT",
        help="the Ray cluster's head for --executor ray (default: start Ray on this machine)",
    )


def _executor(robot: RobotConfig | BodyConfig, args: argparse.Namespace) -> dict[str, Any]:
    """--executor and --address as EvalPlan fields; Ray is checked for before any simulation."""
    if args.executor == "local":
        if args.address is not None:
            raise UsageError("--address names a Ray cluster: add --executor ray")
        return {}
    if isinstance(robot, BodyConfig):
        raise UsageError("--executor ray: tuning a mass-spring body runs on this machine only")
    from snakebot.cluster import require_ray

    require_ray()
    return {"executor": args.executor, "address": args.address}


def _twin_ground(robot: RobotConfig | BodyConfig, args: argparse.Namespace) -> dict[str, Any]:
    """--terrain and --friction-model for the rigid twin; a mass-spring body refuses them."""
    if isinstance(robot, BodyConfig):
        if args.terrain:
            raise UsageError("--terrain: tuning a mass-spring body runs on flat ground only")
        refuse_friction_model(args, "applies to the rigid twin only")
        return {}
    return twin_ground(args, robot)


def _friction(robot: RobotConfig | BodyConfig, text: str | None) -> GroundFriction | None:
    """--friction as the twin's GroundFriction; a body's one floor coefficient fills both."""
    from snakebot.backends.twin import GroundFriction

    if not text:
        return None
    if isinstance(robot, BodyConfig):
        from snakebot.cli.softbody_options import parse_floor_friction

        mu = parse_floor_friction(text)
        return GroundFriction(mu, mu)
    return GroundFriction.parse(text, "--friction")


GAIN_BACKEND_OPTIONS = ("port", "baud")


def _add_gains_parser(commands: Any) -> None:
    parser = commands.add_parser(
        "gains",
        help="tune the servos' Position P/I/D gains for tracking (steps, chirps, a gait)",
        description="Each candidate: one small step per tested joint while the others hold, "
        "then the reference gait. Keeps the candidate with the lowest gait tracking error "
        "whose steps overshoot at most --max-overshoot and settle, and whose gait never holds "
        "a joint at its torque limit for long; writes it to the robot file's [gains] when "
        "--robot names a file (or to a copy with --out).",
    )
    add_robot_option(parser, hardware="with --backend dynamixel")
    add_backend_argument(parser)
    add_option_flags(
        parser,
        GAIN_BACKEND_OPTIONS,
        helps={
            "port": "serial port for --backend dynamixel",
            "baud": "baud rate for --backend dynamixel",
        },
    )
    parser.add_argument("--joints", help="joint indices to step-test, e.g. 0,3 (default all)")
    parser.add_argument(
        "--gait",
        type=gait_arg,
        help="reference gait (default: sidewinding with pitch joints, else serpenoid)",
    )
    parser.add_argument("--gait-duration", type=positive_float, default=6.0, metavar="S")
    parser.add_argument(
        "--step",
        type=positive_float,
        metavar="RAD",
        help="step size (default 0.2 rad on sim, 0.1 rad on hardware)",
    )
    parser.add_argument(
        "--max-overshoot", type=bounded_float(0.0, 1.0), default=0.10, metavar="FRACTION"
    )
    parser.add_argument(
        "--budget", type=positive_int, help="candidates (default 20 sim, 9 hardware)"
    )
    parser.add_argument(
        "--i-values",
        help="Position I values to try, e.g. 0,100 (default: "
        "the current one; the twin has no I term)",
    )
    parser.add_argument("--no-chirp", action="store_true", help="skip the chirp measurements")
    add_write_back_options(parser, "gains")
    parser.add_argument("--report", type=Path, metavar="DIR", help="write plots and summary.json")
    add_force_option(parser)
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.set_defaults(writes=True)


def run_gains(args: argparse.Namespace) -> int:
    """Search the gains on the chosen backend, then write them and report."""
    from snakebot.tuning.gain_search import search_gains, write_gains
    from snakebot.tuning.gains import GainTest
    from snakebot.tuning.progress import gain_line, gains_summary_text

    spec = backend_spec(args)
    hardware = spec.hardware
    robot = load_robot(
        robot_name(args, hardware=hardware, what=f"tune gains --backend {args.backend}")
    )
    given_options(args, spec, GAIN_BACKEND_OPTIONS)
    _check_outputs(args, robot)
    target = robot_write_target(args, robot.source, "the gains")
    joints = tuple(range(robot.joint_count))
    if args.joints:
        joints = tuple(_indices("--joints", args.joints, robot.joint_count))
    gait = args.gait or (
        "sidewinding" if any(j.axis == "pitch" for j in robot.joints) else "serpenoid"
    )
    test = GainTest(
        joints=joints,
        gait=gait,
        gait_s=args.gait_duration,
        step_rad=args.step or (0.1 if hardware else 0.2),
        max_overshoot=args.max_overshoot,
    )
    if args.report is not None:
        from snakebot.tuning.plots import pyplot

        pyplot()
    i_values = _indices("--i-values", args.i_values, 16384) if args.i_values else []
    budget = args.budget or (9 if hardware else 20)

    def progress(done: int, total: int, score: Any, best: Any) -> None:
        if not args.json:
            print(gain_line(done, total, score), file=sys.stderr, flush=True)

    with contextlib.ExitStack() as stack:
        session = _gain_session(robot, args, stack)
        result = search_gains(
            session,
            robot,
            test,
            budget=budget,
            i_values=i_values,
            chirps=not args.no_chirp,
            listener=progress,
        )
    summary = result.summary(robot, test)
    if result.improved and target is not None:
        copy_for_write(robot.source, target)
        summary["written_to"] = str(write_gains(robot, result.best.gains, path=target))
    elif result.improved:
        summary["not_written"] = not_written_note(args, "the gains")
    if args.report is not None and not args.dry_run:
        from snakebot.tuning.plots import gain_plots

        write_report(args.report, summary, lambda directory: gain_plots(result, test, directory))
    if args.json:
        print_json(summary)
        return 0
    print(gains_summary_text(summary))
    return 0


def _gain_session(robot: Any, args: argparse.Namespace, stack: contextlib.ExitStack) -> Any:
    """Fresh simulated backends per candidate; one connection held throughout on hardware."""
    spec = backend_spec(args)
    options = given_options(args, spec, GAIN_BACKEND_OPTIONS)
    if not spec.hardware:
        with flag_errors():
            spec.make(robot, **options)  # a bad option fails now, not in the first candidate
        return lambda: spec.make(robot, **options)
    from snakebot.tuning.gains import held

    with flag_errors():
        backend = stack.enter_context(spec.make(robot, **options))
    return lambda: held(backend)


def _indices(option: str, text: str, count: int) -> list[int]:
    try:
        values = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ConfigError(option, text, "expected comma-separated integers") from None
    bad = [v for v in values if not 0 <= v < count]
    if bad or not values:
        raise ConfigError(option, text, f"expected integers in 0..{count - 1}")
    return values


REPORT_FILES = {
    "gait": ("summary.json", "convergence.png", "heatmap.png"),
    "gains": ("summary.json", "steps.png", "chirp.png"),
}
"""What ``--report DIR`` writes into DIR, per subcommand."""


def _check_outputs(args: argparse.Namespace, robot: Any) -> None:
    """Refuse an existing (without --force) or unwritable --out or --report before any tuning
    (which takes minutes)."""
    if args.tune_command == "gains":
        check_robot_copy(args, robot.source)
    elif args.out is not None:
        check_writable(args.out, "gait file", force=args.force)
    if args.report is not None:
        check_folder(
            args.report, "report", replaces=REPORT_FILES[args.tune_command], force=args.force
        )
