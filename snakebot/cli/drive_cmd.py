"""``snakebot drive``: drive the twin or the robot live from the keyboard, a gamepad or a script."""

from __future__ import annotations

import argparse
import contextlib
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from snakebot.backends.base import Backend
from snakebot.cli.common import add_robot_option, positive_float, print_json, robot_name
from snakebot.cli.run_cmd import make_backend
from snakebot.config import RobotConfig, load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.safety import SafetyLayer
from snakebot.drive.controller import DriveController, GaitChoice
from snakebot.drive.loop import DriveObserver, DriveResult, run_drive
from snakebot.drive.observers import backend_readings, csv_log_observer
from snakebot.drive.signals import StopSignals
from snakebot.drive.sources import DriveInputError, InputSource, ScriptRecorder, ScriptSource
from snakebot.errors import ConfigError
from snakebot.gaits import check_joint_axes, parse_set_options
from snakebot.gaits.live import LiveGait
from snakebot.telemetry import CsvTelemetryWriter

PLANAR_GAITS = ("serpenoid",)
SPATIAL_GAITS = ("sidewinding", "rolling", "lateral_undulation", "turn_in_place",
                 "linear_progression")


def add_parser(subparsers: Any) -> None:
    """Register the ``drive`` command."""
    parser = subparsers.add_parser(
        "drive",
        help="drive the twin (default) or the robot live: keyboard, gamepad or script",
        description="Drive a snake live. Keys: w/s or up/down speed, a/d or left/right turn, "
        "x halt, +/- amplitude, ]/[ wavelength, 1-9 gait, tab next gait, space pause to the "
        "rest pose, q or ctrl-c stop (rest pose, then the robot's stop policy). "
        "docs/driving.md has the details and the script format.",
    )
    add_robot_option(parser, hardware="with --backend dynamixel")
    parser.add_argument(
        "--backend",
        choices=("sim", "dynamixel"),
        default="sim",
        help="sim: the MuJoCo twin (default); dynamixel: the servo chain",
    )
    parser.add_argument("--port", help="serial port for --backend dynamixel (default: robot)")
    parser.add_argument("--baud", type=int, help="baud rate for --backend dynamixel")
    parser.add_argument(
        "--allow-extra-servos",
        action="store_true",
        help="--backend dynamixel: servos on the bus that the robot file does not name are "
        "expected (left alone); without it connect refuses, naming them",
    )
    parser.add_argument(
        "--gaits",
        help="comma-separated gaits for keys 1-9 (default: serpenoid on all-yaw robots; "
        f"{','.join(SPATIAL_GAITS)} on yaw/pitch ones)",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="GAIT.KEY=VALUE",
        help="a gait parameter (repeatable), e.g. --set sidewinding.amplitude_even=0.5; "
        "KEY=VALUE alone when one gait is listed",
    )
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--script", type=Path, help="play '<time_s> <key>' lines from FILE")
    source.add_argument(
        "--gamepad", action="store_true", help="drive with a gamepad (extra: snakebot[gamepad])"
    )
    parser.add_argument("--record", type=Path, help="write the keys applied as a script")
    parser.add_argument(
        "--rate", type=positive_float, default=100.0, help="control rate in Hz (default 100)"
    )
    parser.add_argument(
        "--smoothing",
        type=float,
        default=0.5,
        metavar="S",
        help="seconds for a control to move one unit (default 0.5)",
    )
    parser.add_argument(
        "--transition",
        type=float,
        default=1.0,
        metavar="S",
        help="shortest blend between gaits in s (default 1; longer when the servos need it)",
    )
    parser.add_argument(
        "--friction",
        metavar="AXIAL,LATERAL",
        help="twin ground friction along and across each module (overrides the robot's)",
    )
    parser.add_argument(
        "--realtime",
        action="store_true",
        help="pace the twin to the wall clock (always on without --script)",
    )
    parser.add_argument("--log", type=Path, help="per-cycle telemetry CSV")
    parser.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    parser.set_defaults(handler=run, viewer=False, video=None, directional=None, terrain=None)


def gait_choices(robot: RobotConfig, args: argparse.Namespace) -> list[GaitChoice]:
    """The gait list from --gaits (or the robot's default) with the --set overrides."""
    planar = all(joint.axis == "yaw" for joint in robot.joints)
    names = (
        [n.strip() for n in args.gaits.split(",") if n.strip()]
        if args.gaits
        else list(PLANAR_GAITS if planar else SPATIAL_GAITS)
    )
    if not names or len(names) > 9:
        raise ConfigError("--gaits", "", f"expected 1 to 9 gait names, got {args.gaits!r}")
    overrides: dict[str, list[str]] = {name: [] for name in names}
    for item in args.set:
        key = item.partition("=")[0]
        gait, dot, _ = key.partition(".")
        if dot and gait in overrides:
            overrides[gait].append(item[len(gait) + 1 :])
        elif not dot and len(names) == 1:
            overrides[names[0]].append(item)
        else:
            raise ConfigError(
                "--set",
                "",
                f"{item}: expected GAIT.KEY=VALUE with GAIT one of {', '.join(names)} "
                "(KEY=VALUE alone only when one gait is listed)",
            )
    for name in names:
        check_joint_axes(name, [joint.axis for joint in robot.joints], robot.name)
    return [GaitChoice(name, parse_set_options(name, overrides[name])) for name in names]


def make_live(robot: RobotConfig, args: argparse.Namespace) -> LiveGait:
    """The live gait for this robot: its limits and speed, steering on the yaw joints."""
    for option, value in (("--smoothing", args.smoothing), ("--transition", args.transition)):
        if not (value >= 0 and np.isfinite(value)):
            raise ConfigError(option, "", f"expected seconds >= 0, got {value!r}")
    return LiveGait(
        robot.joint_count,
        lower_rad=robot.lower_rad,
        upper_rad=robot.upper_rad,
        max_speed_rad_s=robot.max_speed_rad_s,
        period_s=1.0 / args.rate,
        steer=[1.0 if joint.axis == "yaw" else 0.0 for joint in robot.joints],
        smoothing_s=args.smoothing,
        transition_s=args.transition,
    )


def make_source(args: argparse.Namespace) -> InputSource:
    """The input: the script, the gamepad, or the terminal."""
    if args.script is not None:
        return ScriptSource.load(args.script)
    if args.gamepad:
        from snakebot.drive.gamepad import GamepadSource

        return GamepadSource()
    from snakebot.drive.terminal import TerminalSource

    return TerminalSource()


def run(args: argparse.Namespace) -> int:
    """Load, connect, drive until a stop, summarise; servos end as the stop policy says."""
    hardware = args.backend == "dynamixel"
    robot = load_robot(robot_name(args, hardware=hardware, what="drive --backend dynamixel"))
    choices = gait_choices(robot, args)
    live = make_live(robot, args)
    for choice in choices:
        live.check(choice.name, choice.params)
    source = make_source(args)
    if args.backend == "sim" and args.script is None:
        args.realtime = True  # a person drives: the twin keeps to the wall clock
    backend = make_backend(robot, args)
    safety = SafetyLayer.for_robot(robot)
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    with contextlib.ExitStack() as stack:
        recorder = _recorder(stack, args, robot)
        controller = DriveController(live, choices, on_event=recorder)
        observers: list[DriveObserver] = []
        if args.log:
            log = stack.enter_context(CsvTelemetryWriter(args.log, robot.joint_count))
            observers.append(csv_log_observer(log))
        signals = stack.enter_context(StopSignals())
        stack.enter_context(source)
        stack.enter_context(backend)
        display = _display(stack, args, robot, backend, controller)
        if display is not None:
            observers.append(display)
        result = run_drive(
            backend,
            live,
            safety,
            controller,
            source,
            rate_hz=args.rate,
            metrics=metrics,
            observers=observers,
            stop_check=signals,
        )
    summary = _summary(robot, args, choices, result)
    if args.json:
        print_json(summary)
    else:
        _print_summary(summary)
    if result.stopped_by.startswith("input lost"):
        raise DriveInputError(
            f"{source.name}: {result.stopped_by}; the snake was stopped "
            f"({robot.safety.stop_policy} at the rest pose)"
        )
    return 130 if result.stopped_by.startswith("interrupted") else 0


def _recorder(
    stack: contextlib.ExitStack, args: argparse.Namespace, robot: RobotConfig
) -> ScriptRecorder | None:
    if args.record is None:
        return None
    try:
        stream = stack.enter_context(args.record.open("w", encoding="utf-8"))
    except OSError as exc:
        raise ConfigError(args.record, "", f"cannot write the recording ({exc.strerror})") from exc
    header = (
        f"snakebot drive recording: robot {robot.name}, backend {args.backend}, rate "
        f"{args.rate:g} Hz\nreplay: snakebot drive --robot {robot.name} --script {args.record}"
    )
    return ScriptRecorder(stream, header)


def _display(
    stack: contextlib.ExitStack,
    args: argparse.Namespace,
    robot: RobotConfig,
    backend: Backend,
    controller: DriveController,
) -> DriveObserver | None:
    if not sys.stderr.isatty():
        return None
    from snakebot.drive.display import DriveDisplay

    where = f" ({args.port or robot.bus.port})" if args.backend == "dynamixel" else ""

    health, alerts = backend_readings(backend)
    display = DriveDisplay(
        sys.stderr,
        title=f"snakebot drive: {robot.name} on {args.backend}{where}, {robot.joint_count} "
        f"joints, stop policy {robot.safety.stop_policy}",
        gaits=[c.name for c in controller.gaits],
        gait_index=lambda: controller.gait_index,
        notice=lambda: controller.notice or (controller.stop_reason or ""),
        rate_hz=args.rate,
        servo_ids=robot.servo_ids,
        health=health,
        alerts=alerts,
        overruns=lambda: backend.stats.overruns,
    )
    stack.enter_context(_closing_display(display))
    return display


@contextlib.contextmanager
def _closing_display(display: Any) -> Iterator[None]:
    try:
        yield
    except BaseException as exc:
        display.close(f"error: {exc}" if str(exc) else type(exc).__name__)
        raise
    display.close()


def _summary(
    robot: RobotConfig, args: argparse.Namespace, choices: list[GaitChoice], result: DriveResult
) -> dict[str, object]:
    summary: dict[str, object] = {
        "robot": robot.name,
        "gaits": [c.name for c in choices],
        "backend": args.backend,
        **result.summary,
    }
    if args.log:
        summary["log"] = str(args.log)
    if args.record:
        summary["record"] = str(args.record)
    return summary


def _print_summary(summary: dict[str, object]) -> None:
    def fmt(key: str, unit: str = "", digits: int = 3) -> str:
        value = summary.get(key)
        if value is None:
            return "n/a"
        return f"{value:.{digits}f}{unit}" if isinstance(value, float) else f"{value}{unit}"

    gaits = summary["gaits"] if isinstance(summary["gaits"], list) else []
    lines = [
        f"{summary['robot']} driven on {summary['backend']}: stopped by {summary['stopped_by']}",
        f"  time         {fmt('duration_s', ' s', 2)}, {fmt('control_cycles')} cycles at "
        f"{fmt('achieved_rate_hz', ' Hz', 1)} ({fmt('overruns')} overruns)",
        f"  input        {fmt('keys')} keys; gaits {', '.join(map(str, gaits))}",
        f"  distance     {fmt('distance_m', ' m')} at heading {fmt('heading_deg', ' deg', 1)}, "
        f"turned {fmt('turn_deg', ' deg', 1)}",
        f"  tracking     {fmt('tracking_rms_rad', ' rad RMS', 4)}; max command "
        f"{fmt('max_abs_command_rad', ' rad')}",
    ]
    for key in ("log", "record"):
        if key in summary:
            lines.append(f"  {key:<12} {summary[key]}")
    print("\n".join(lines))
