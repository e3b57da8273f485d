"""``snakebot sysid``: fit the twin's servo parameters to telemetry logs, or record such a log."""

from __future__ import annotations

import argparse
import contextlib
from pathlib import Path
from typing import Any

from snakebot.cli.backend_options import (
    add_backend_argument,
    add_option_flags,
    backend_spec,
    flag_errors,
    given_options,
)
from snakebot.cli.common import (
    add_force_option,
    add_robot_option,
    add_write_back_options,
    check_folder,
    check_robot_copy,
    check_writable,
    copy_for_write,
    finite_float,
    not_written_note,
    positive_float,
    positive_int,
    print_json,
    report_dry_run,
    robot_name,
    robot_write_target,
    write_report,
)
from snakebot.config import load_robot
from snakebot.config.schema import MAX_ACTUATOR_DELAY_S
from snakebot.errors import UsageError

RECORD_BACKEND_OPTIONS = ("port", "baud")
REPORT_FILES = ("summary.json", "replay.png")
"""What ``--report DIR`` writes into DIR."""


def add_parser(subparsers: Any) -> None:
    """Register the ``sysid`` command."""
    parser = subparsers.add_parser(
        "sysid",
        help="fit the twin's servo parameters (stiffness, damping, ...) to telemetry logs",
        description="Replays each log's commands on the twin and fits the servo parameters so "
        "the twin's joints follow the log's, then writes them to [twin.servo] of "
        "--robot FILE (or of a copy, --out FILE). With --record, first records a log: one "
        "joint held off the ground (--hold) and chirped, the others still.",
    )
    add_robot_option(parser, hardware="with --record --backend dynamixel")
    parser.add_argument("logs", nargs="*", type=Path, metavar="LOG", help="telemetry CSV logs")
    parser.add_argument(
        "--params",
        default="stiffness,damping,armature",
        help="parameters to fit, from stiffness,damping,armature,friction_loss,delay,p_divisor "
        f"(delay: the actuator delay, fitted within 0 to {MAX_ACTUATOR_DELAY_S:g} s; p_divisor: "
        "the P-gain divisor, 256 or 128, instead of stiffness)",
    )
    parser.add_argument(
        "--workers", type=positive_int, default=2, help="parallel replays (default 2)"
    )
    parser.add_argument("--max-evaluations", type=positive_int, default=40, metavar="N")
    add_write_back_options(parser, "servo parameters")
    parser.add_argument("--report", type=Path, metavar="DIR", help="write plots and summary.json")
    add_force_option(parser)
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    group = parser.add_argument_group("recording a log (--record)")
    group.add_argument("--record", type=Path, metavar="LOG", help="record a chirp log and exit")
    add_backend_argument(group)
    add_option_flags(
        group,
        RECORD_BACKEND_OPTIONS,
        helps={
            "port": "serial port for --backend dynamixel",
            "baud": "baud rate for --backend dynamixel",
        },
    )
    group.add_argument("--joint", type=int, default=1, help="joint to chirp (default 1)")
    group.add_argument(
        "--hold",
        type=finite_float,
        default=0.5,
        metavar="RAD",
        help="angle to hold the joint at while it chirps (default 0.5)",
    )
    group.add_argument("--amplitude", type=positive_float, default=0.12, metavar="RAD")
    group.add_argument("--duration", type=positive_float, default=4.0, metavar="S")
    group.add_argument("--stop-hz", type=positive_float, default=6.0, metavar="HZ")
    parser.set_defaults(handler=run, writes=True)


def run(args: argparse.Namespace) -> int:
    """Record a log, or fit the twin to logs and write the result."""
    hardware = args.record is not None and backend_spec(args).hardware
    robot = load_robot(
        robot_name(args, hardware=hardware, what=f"sysid --record --backend {args.backend}")
    )
    if args.record is not None:
        check_writable(args.record, "log", force=args.force)
        if args.dry_run:
            return report_dry_run(
                args,
                {
                    "robot": robot.name,
                    "backend": args.backend,
                    "record": args.record,
                    "joint": args.joint,
                    "hold_rad": args.hold,
                    "amplitude_rad": args.amplitude,
                    "duration_s": args.duration,
                },
            )
        return _record(robot, args)
    check_robot_copy(args, robot.source)
    if args.report is not None:
        check_folder(args.report, "report", replaces=REPORT_FILES, force=args.force)
    target = robot_write_target(args, robot.source, "the servo parameters")
    if not args.logs:
        raise UsageError("give one or more telemetry logs (LOG ...), or --record LOG")
    from snakebot.tuning.config_edit import set_table_values
    from snakebot.tuning.sysid import FIELDS, fit_servo, load_log

    if args.report is not None:
        from snakebot.tuning.plots import pyplot

        pyplot()
    names = [p.strip() for p in args.params.split(",") if p.strip()]
    logs = [load_log(path, robot) for path in args.logs]
    result = fit_servo(
        robot, logs, names, workers=max(1, args.workers), max_evaluations=args.max_evaluations
    )
    summary: dict[str, Any] = {
        "robot": robot.name,
        "logs": [str(p) for p in args.logs],
        "fitted": list(result.names),
        "before": result.before.report(robot),
        "after": result.after.report(robot),
        "tracking_rms_before_rad": result.rms_before_rad,
        "tracking_rms_after_rad": result.rms_after_rad,
        "replays": result.simulations,
    }
    if result.rms_after_rad < result.rms_before_rad:
        if target is not None:
            values = {FIELDS[n]: float(getattr(result.after, FIELDS[n])) for n in result.names}
            copy_for_write(robot.source, target)
            set_table_values(target, "twin.servo", values)
            summary["written_to"] = f"{target} [twin.servo]"
        else:
            summary["not_written"] = not_written_note(args, "the servo parameters")
    if args.report is not None and not args.dry_run:
        from snakebot.tuning.plots import sysid_plots

        write_report(args.report, summary, lambda directory: sysid_plots(result, logs, directory))
    if args.json:
        print_json(summary)
        return 0
    print(
        f"{robot.name}: twin vs log {result.rms_before_rad:.5f} rad RMS before, "
        f"{result.rms_after_rad:.5f} rad after ({result.simulations} replays)"
    )
    for key, value in summary["after"].items():
        print(f"  {key:<22} {summary['before'][key]:.6g} -> {value:.6g}")
    if "written_to" in summary:
        print(f"  written to {summary['written_to']}")
    else:
        note = summary.get("not_written")
        print(f"  robot file unchanged: {note}" if note else "  robot file unchanged")
    return 0


def _record(robot: Any, args: argparse.Namespace) -> int:
    from snakebot.tuning.excitation import chirp_plan, record

    with contextlib.ExitStack() as stack:
        spec = backend_spec(args)
        with flag_errors():
            options = given_options(args, spec, RECORD_BACKEND_OPTIONS)
            backend: Any = stack.enter_context(spec.make(robot, **options))
        start = backend.read_state().position_rad
        commands = chirp_plan(
            robot,
            start,
            args.joint,
            args.hold,
            amplitude_rad=args.amplitude,
            duration_s=args.duration,
            stop_hz=args.stop_hz,
        )
        rows = record(backend, robot, commands, args.record)
    print(f"recorded {rows} cycles to {args.record}")
    return 0
