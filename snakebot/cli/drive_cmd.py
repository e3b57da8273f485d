"""``snakebot drive``: drive the twin or the robot live from the keyboard, a gamepad or a script."""

from __future__ import annotations

import argparse
import contextlib
import os
import shlex
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from snakebot.backends.base import Backend
from snakebot.backends.capabilities import OnBus
from snakebot.cli.backend_options import (
    add_backend_argument,
    add_option_flags,
    backend_spec,
    flag,
    flag_errors,
    given_options,
)
from snakebot.cli.common import (
    add_dry_run,
    add_robot_option,
    print_json,
    report_dry_run,
    robot_name,
)
from snakebot.cli.gait_options import add_gait_options, gait_choices
from snakebot.cli.telemetry_options import (
    add_telemetry_options,
    check_outputs,
    drive_observer,
    open_telemetry,
)
from snakebot.config import RobotConfig, load_robot
from snakebot.drive.controller import DriveController, GaitChoice
from snakebot.drive.observers import backend_readings
from snakebot.drive.run import DriveObserver, DriveResult
from snakebot.drive.setup import (
    DEFAULT_SMOOTHING_S,
    DEFAULT_TRANSITION_S,
    SPATIAL_GAITS,
    live_gait,
)
from snakebot.drive.signals import StopSignals
from snakebot.drive.sources import DriveInputError, InputSource, ScriptRecorder, ScriptSource
from snakebot.errors import ConfigError, OutputError
from snakebot.session import DEFAULT_BACKEND, Snake, watched
from snakebot.telemetry.sidecar import gait_facts

BACKEND_OPTIONS = ("port", "baud", "allow_extra_servos", "friction", "realtime")
"""The backend option flags ``drive`` offers."""


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
    add_backend_argument(parser)
    add_option_flags(
        parser,
        ("port", "baud", "allow_extra_servos"),
        helps={
            "port": "serial port for --backend dynamixel (default: robot)",
            "baud": "baud rate for --backend dynamixel",
            "allow_extra_servos": "--backend dynamixel: servos on the bus that the robot file "
            "does not name are expected (left alone); without it connect refuses, naming them",
        },
    )
    add_gait_options(
        parser,
        gaits_help="comma-separated gaits for keys 1-9 (default: serpenoid on all-yaw robots; "
        f"{','.join(SPATIAL_GAITS)} on yaw/pitch ones)",
    )
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--script", type=Path, help="play '<time_s> <key>' lines from FILE")
    source.add_argument(
        "--gamepad", action="store_true", help="drive with a gamepad (extra: snakebot[gamepad])"
    )
    parser.add_argument("--record", type=Path, help="write the keys applied as a script")
    add_option_flags(
        parser,
        ("friction", "realtime"),
        helps={
            "friction": "twin ground friction along and across each module (overrides the robot's)",
            "realtime": "pace the twin to the wall clock (always on without --script)",
        },
    )
    parser.add_argument("--log", type=Path, help="per-cycle telemetry CSV")
    add_telemetry_options(parser)
    parser.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    add_dry_run(parser, "no servo moves, no log or script")
    parser.set_defaults(handler=run, writes=True)


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
    spec = backend_spec(args)
    robot = load_robot(
        robot_name(args, hardware=spec.hardware, what=f"drive --backend {args.backend}")
    )
    given = given_options(args, spec, BACKEND_OPTIONS)
    choices = gait_choices(robot, args)
    live = live_gait(
        robot,
        rate_hz=args.rate,
        smoothing_s=args.smoothing,
        transition_s=args.transition,
        gaits=choices,
    )
    source = make_source(args)
    if args.script is None or args.foxglove is not None:  # a person drives or watches
        given = watched(spec, given)
    check_outputs(args, (args.record, "recording"))  # before anything is written or moves
    if args.dry_run:
        return report_dry_run(
            args,
            {
                "robot": robot.name,
                "gaits": ",".join(c.name for c in choices),
                "backend": spec.name,
                "log": args.log,
                "record": args.record,
            },
        )
    with flag_errors():
        snake = Snake.prepare(robot, spec, **given)
    backend = snake.backend
    # A rate the servo bus cannot hold is refused before the port opens (--rate, exit 2).
    backend.check_rate(args.rate)
    with contextlib.ExitStack() as stack:
        recorder = _recorder(stack, args, robot)
        controller = DriveController(live, choices, on_event=recorder)
        observers: list[DriveObserver] = []
        telemetry = open_telemetry(
            stack,
            args,
            command="drive",
            robot=robot,
            backend=backend,
            rate_hz=args.rate,
            gait={"gaits": [gait_facts(c.name, None, c.params) for c in choices]},
        )
        observers += [o for o in (drive_observer(telemetry),) if o is not None]
        signals = stack.enter_context(StopSignals())
        stack.enter_context(source)
        with flag_errors():
            stack.enter_context(snake)
        display = _display(stack, args, robot, backend, controller)
        if display is not None:
            observers.append(display)
        result = snake.drive(
            live, controller, source, rate_hz=args.rate, observers=observers, stop_check=signals
        )
    summary = {**_summary(robot, args, choices, result), **telemetry.summary}
    stopped = f"the snake was stopped ({robot.safety.stop_policy} at the rest pose)"
    gone = _print_or_lose(lambda: print_json(summary) if args.json else _print_summary(summary))
    if result.stopped_by.startswith("input lost"):
        raise DriveInputError(f"{source.name}: {result.stopped_by}; {stopped}")
    if result.stopped_by.startswith("interrupted"):
        return 130
    if gone is not None:
        raise OutputError("stdout", f"the summary could not be printed ({gone}); {stopped}")
    return 0


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
        f"snakebot drive recording: robot {robot.name}, backend {backend_spec(args).name}, rate "
        f"{args.rate:g} Hz\nreplay: {replay_command(args, args.record)}"
    )
    return ScriptRecorder(stream, header)


def replay_command(args: argparse.Namespace, script: Path) -> str:
    """The ``snakebot drive`` line that plays ``script`` (a recording of the drive ``args``
    made) as it was recorded: the robot, backend and its options, gaits and their parameters,
    rate, smoothing and transition. Outputs (--log, --record, --foxglove, ...) and pacing
    (--realtime: the twin's results do not depend on it) are left out."""
    spec = backend_spec(args)
    words = ["snakebot", "drive", "--robot", robot_name(args, hardware=spec.hardware, what="")]
    if args.backend != DEFAULT_BACKEND:
        words += ["--backend", args.backend]
    for name, value in given_options(args, spec, BACKEND_OPTIONS).items():
        if name != "realtime":
            words += [flag(name)] if value is True else [flag(name), str(value)]
    if args.gaits:
        words += ["--gaits", args.gaits]
    for item in args.set:
        words += ["--set", item]
    words += ["--rate", repr(args.rate)]
    for option, value, default in (
        ("--smoothing", args.smoothing, DEFAULT_SMOOTHING_S),
        ("--transition", args.transition, DEFAULT_TRANSITION_S),
    ):
        if value != default:
            words += [option, repr(value)]
    return shlex.join([*words, "--script", str(script)])


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

    where = f" ({backend.port})" if isinstance(backend, OnBus) else ""

    health, alerts = backend_readings(backend)
    name = backend_spec(args).name
    display = DriveDisplay(
        sys.stderr,
        title=f"snakebot drive: {robot.name} on {name}{where}, {robot.joint_count} "
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
        "backend": backend_spec(args).name,
        **result.summary,
    }
    if args.log:
        summary["log"] = str(args.log)
    if args.record:
        summary["record"] = str(args.record)
    return summary


def _print_or_lose(print_summary: Callable[[], None]) -> str | None:
    """Print the summary; the reason instead when what it goes to is gone (the terminal
    window shut mid-drive, the reader of a pipe quit). That output is then discarded, stderr's
    too if it went with it, so what is left to say neither fails nor turns into an internal
    error."""
    from snakebot.drive.terminal import GONE_ERRNOS, discard_output, hung_up

    try:
        print_summary()
        sys.stdout.flush()
    except OSError as exc:
        if exc.errno not in GONE_ERRNOS:
            raise
        discard_output(sys.stdout)
        if hung_up(sys.stderr):
            discard_output(sys.stderr)
        return os.strerror(exc.errno or 0)
    return None


def _print_summary(summary: dict[str, object]) -> None:
    def fmt(key: str, unit: str = "", digits: int = 3) -> str:
        value = summary.get(key)
        if value is None:
            return "n/a"
        return f"{value:.{digits}f}{unit}" if isinstance(value, float) else f"{value}{unit}"

    gaits = summary["gaits"] if isinstance(summary["gaits"], list) else []
    dropped = (
        f" ({summary['dropped_keys']} more dropped: too many at once)"
        if summary.get("dropped_keys")
        else ""
    )
    lines = [
        f"{summary['robot']} driven on {summary['backend']}: stopped by {summary['stopped_by']}",
        f"  time         {fmt('duration_s', ' s', 2)}, {fmt('control_cycles')} cycles at "
        f"{fmt('achieved_rate_hz', ' Hz', 1)} ({fmt('overruns')} overruns)",
        f"  input        {fmt('keys')} keys{dropped}; gaits {', '.join(map(str, gaits))}",
        f"  distance     {fmt('distance_m', ' m')} at heading {fmt('heading_deg', ' deg', 1)}, "
        f"turned {fmt('turn_deg', ' deg', 1)}",
        f"  tracking     {fmt('tracking_rms_rad', ' rad RMS', 4)}; max command "
        f"{fmt('max_abs_command_rad', ' rad')}",
    ]
    for key in ("log", "record"):
        if key in summary:
            lines.append(f"  {key:<12} {summary[key]}")
    print("\n".join(lines))
