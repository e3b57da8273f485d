"""``snakebot run``: play a gait on the twin or the servo chain and summarise the run."""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

from snakebot.backends.base import Backend
from snakebot.backends.capabilities import Simulated
from snakebot.cli.backend_options import (
    add_backend_argument,
    add_option_flags,
    backend_spec,
    flag_errors,
    given_options,
)
from snakebot.cli.common import (
    RATE_HZ,
    add_dry_run,
    add_robot_option,
    gait_arg,
    positive_float,
    print_json,
    report_dry_run,
    robot_name,
)
from snakebot.cli.goto_options import odometry_for, steered_gait, steering_summary
from snakebot.cli.telemetry_options import add_telemetry_options, check_outputs, open_telemetry
from snakebot.cli.terrain_options import FRICTION_MODEL_HELP, terrain_help
from snakebot.config import RobotConfig
from snakebot.control.compliance import (
    ComplianceSettings,
    CompliantGait,
    check_torque_sensing,
)
from snakebot.control.cycle import CycleRecord
from snakebot.control.torque_limit import limit_servo_torque
from snakebot.errors import ConfigError, OutputError, UsageError
from snakebot.estimation import ChassisOdometry
from snakebot.estimation.goto import STEERABLE_GAITS, GoToPoint
from snakebot.gaits import Gait, load_gait_file, parse_set_options
from snakebot.run_summary import RunSummary
from snakebot.session import (
    DEFAULT_DURATION_S,
    DEFAULT_GAIT,
    DEFAULT_RATE_HZ,
    Robot,
    Snake,
    load_robot,
    resolve_gait,
    watched,
)
from snakebot.telemetry.sidecar import gait_facts

TO_DURATION_S = 60.0
"""How long ``run --to`` may take to reach its point when --duration does not say."""

BACKEND_OPTIONS = (
    "friction",
    "friction_model",
    "directional",
    "terrain",
    "realtime",
    "port",
    "baud",
    "allow_extra_servos",
)
"""The backend option flags ``run`` offers; each one is refused with a backend without it."""


def add_parser(subparsers: Any) -> None:
    """Register the ``run`` command."""
    parser = subparsers.add_parser("run", help="run a gait on the twin (default) or the robot")
    add_robot_option(parser, hardware="with --backend dynamixel")
    parser.add_argument(
        "--gait", type=gait_arg, help=f"gait name (see `snakebot gaits`; default {DEFAULT_GAIT})"
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a gait parameter (repeatable), e.g. --set omega=pi",
    )
    parser.add_argument("--gait-file", type=Path, help="replay a saved gait (TOML)")
    parser.add_argument(
        "--policy",
        metavar="DIR",
        help="play a trained policy (`snakebot rl "
        "train`) as the gait, on a servo snake; needs snakebot[rl]",
    )
    # dest: ``args.command`` is the subcommand's name (main.py's error messages use it)
    parser.add_argument(
        "--command",
        dest="policy_command",
        metavar="A,B",
        help="with --policy: "
        "speed,turn_rate (m/s, rad/s) for a velocity policy; goal X,Y (m, X "
        "ahead) for a goal policy",
    )
    parser.add_argument(
        "--to",
        metavar="X,Y",
        help="go to a point X,Y m from the snake (X ahead, Y left) and stop there, steering "
        "the gait by the odometry of the measured joints (docs/estimation.md); "
        f"gaits {', '.join(STEERABLE_GAITS)}",
    )
    parser.add_argument(
        "--odometry",
        action="store_true",
        help="with a goal --policy: its pose from the odometry of the measured joints and the "
        "head IMU (docs/estimation.md), so it runs on the servos with no motion capture",
    )
    parser.add_argument(
        "--comply",
        action="store_true",
        help="gait-based compliance: the gait's amplitude and offset give way, window by "
        "window along the body, where the servos measure a hard push (docs/compliance.md); "
        "needs servos that measure current, or the twin",
    )
    parser.add_argument(
        "--comply-phase",
        type=float,
        metavar="GAIN",
        help="with --comply: the gait's phase yields too, at GAIN 1/s (docs/compliance.md "
        "sweeps 1-3 over 15 peg fields: no gain helps reliably; default: off)",
    )
    parser.add_argument(
        "--torque-limit",
        type=float,
        metavar="NM",
        help="cap every servo's torque at NM N*m while it follows the gait: current-based "
        "position control (Dynamixel Operating Mode 5, Goal Current = NM / kt) on servos that "
        "have it, the twin's actuator force range on the twin (docs/compliance.md)",
    )
    add_backend_argument(parser)
    parser.add_argument(
        "--duration",
        type=positive_float,
        default=None,
        help=f"gait time in seconds, before the ramp-out (default {DEFAULT_DURATION_S:g}; "
        f"with --to the longest it may take, default {TO_DURATION_S:g})",
    )
    parser.add_argument(
        "--rate",
        type=RATE_HZ,
        default=DEFAULT_RATE_HZ,
        help=f"control rate in Hz (default {DEFAULT_RATE_HZ:g})",
    )
    add_option_flags(
        parser,
        BACKEND_OPTIONS,
        helps={
            "friction": "twin ground friction along and across each module; equal values = "
            "isotropic (overrides the robot's ground model); one number MU for a mass-spring "
            "body's floor",
            "terrain": terrain_help(),
            "friction_model": FRICTION_MODEL_HELP,
            "realtime": "pace the twin to the wall clock",
            "port": "serial port for --backend dynamixel (default: robot config)",
            "baud": "baud rate for --backend dynamixel",
            "allow_extra_servos": "--backend dynamixel: servos on the bus that the robot file "
            "does not name are expected (left alone); without it connect refuses, naming them",
        },
    )
    parser.add_argument(
        "--viewer", action="store_true", help="open MuJoCo's viewer (needs a display)"
    )
    parser.add_argument("--video", type=Path, help="render the twin to an MP4 file (offscreen)")
    parser.add_argument("--log", type=Path, help="per-cycle telemetry CSV")
    add_telemetry_options(parser)
    parser.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    add_dry_run(parser, "no servo moves, no log or video")
    parser.set_defaults(handler=run, writes=True)


def prepare(args: argparse.Namespace, options: tuple[str, ...]) -> tuple[Snake, Any]:
    """The robot --robot names on the backend --backend names, not yet connected, and the
    gait (name, Gait) from --gait/--gait-file/--set; usage and config errors name the flags."""
    spec = backend_spec(args)
    robot = load_robot(
        robot_name(args, hardware=spec.hardware, what=f"{args.command} --backend {args.backend}")
    )
    given = given_options(args, spec, options)
    # Someone watching (the viewer, Foxglove) sees the twin at the wall clock's pace.
    if getattr(args, "viewer", False) or getattr(args, "foxglove", None) is not None:
        given = watched(spec, given)
    with flag_errors():
        snake = Snake.prepare(robot, spec, **given)
    return snake, spec


def build_gait(robot: Robot, args: argparse.Namespace) -> tuple[str, Gait]:
    """The gait from --gait-file and/or --gait, with --set overrides on top."""
    name = args.gait or DEFAULT_GAIT
    if args.gait_file is not None:
        file_name = load_gait_file(args.gait_file)[0]
        if args.gait and args.gait != file_name:
            raise ConfigError(
                "--gait",
                "",
                f"{args.gait_file} holds gait {file_name!r}, "
                f"not {args.gait!r}; drop --gait or pick the matching file",
            )
        name = file_name
    params = parse_set_options(name, args.set)
    gait = None if args.gait_file is not None else name
    return resolve_gait(robot, gait, params=params, gait_file=args.gait_file)


def run(args: argparse.Namespace) -> int:
    """Load, build, run, summarise; telemetry stays on disk whatever happens."""
    if args.policy is None and args.policy_command is not None:
        raise UsageError("--command goes with --policy (a trained policy's command)")
    if args.to is not None and args.policy is not None:
        raise UsageError("--to steers a gait; a --policy steers itself (drop one)")
    if args.odometry and args.policy is None:
        raise UsageError("--odometry is a goal --policy's pose source (--to has its own)")
    if args.duration is None:
        args.duration = TO_DURATION_S if args.to is not None else DEFAULT_DURATION_S
    snake, spec = prepare(args, BACKEND_OPTIONS)
    observers: list[ChassisOdometry] = []
    steering: GoToPoint | None = None
    if args.policy is None:
        gait_name, gait = build_gait(snake.robot, args)
        if args.to is not None:
            gait_name, gait, steering = steered_gait(snake.robot, gait_name, gait, args.to)
            observers.append(steering.odometry)
    else:  # a closed-loop gait: it reads the backend it drives
        from snakebot.cli.policy_options import policy_gait

        odometry = odometry_for(snake.robot) if args.odometry else None
        gait_name, gait = policy_gait(snake.robot, snake.backend, args, pose=odometry)
        observers.extend([] if odometry is None else [odometry])
    if args.comply_phase is not None and not args.comply:
        raise UsageError("--comply-phase goes with --comply")
    if args.comply_phase is not None and not (0 <= args.comply_phase < math.inf):
        raise UsageError(f"--comply-phase: expected a gain >= 0 1/s, got {args.comply_phase}")
    compliance: CompliantGait | None = None
    if args.comply:
        robot = snake.robot
        check_torque_sensing(
            snake.backend,
            where="--comply",
            servo=robot.servo.name if isinstance(robot, RobotConfig) else "",
        )
        if not isinstance(snake.robot, RobotConfig):
            raise ConfigError("--comply", "", "compliance needs a servo robot, not a soft body")
        settings = ComplianceSettings(
            phase_gain=0.0 if args.comply_phase is None else args.comply_phase
        )
        stall_nm = snake.robot.servo.physics.stall_torque_nm
        gait = compliance = CompliantGait(gait, stall_nm, settings)
    if args.torque_limit is not None:
        limit_servo_torque(snake.backend, snake.robot, args.torque_limit, "--torque-limit")
    if (args.video or args.viewer) and spec.hardware:
        raise ConfigError(
            "--video" if args.video else "--viewer",
            "",
            f"renders the simulation: it needs a simulated backend, not {spec.name}",
        )
    # Outputs are checked before anything opens and open before the backend connects: one
    # that exists (without --force) or cannot be written stops the run before a file is
    # touched or a servo moves. Written rows stay on disk whatever ends the run.
    if args.video and args.video.suffix.lower() not in VIDEO_SUFFIXES:
        raise ConfigError(
            "--video",
            str(args.video),
            f"expected a video file name ending in {', '.join(VIDEO_SUFFIXES)}",
        )
    check_outputs(args, (args.video, "video"))
    if args.video:
        from snakebot.backends.twin.video import require_video_writer

        require_video_writer()  # before --log opens, like every other check
    if args.viewer:
        from snakebot.backends.twin.viewer import check_display

        check_display()  # before --log opens: a refused run leaves an existing log as it was
    # A rate the servo bus cannot hold is refused before anything opens (--rate, exit 2).
    snake.backend.check_rate(args.rate)
    if args.dry_run:
        return report_dry_run(
            args,
            {
                "robot": snake.robot.name,
                "gait": gait_name,
                "backend": spec.name,
                "duration_s": args.duration,
                "rate_hz": args.rate,
                "log": args.log,
                "video": args.video,
            },
        )
    with contextlib.ExitStack() as stack:
        telemetry = open_telemetry(
            stack,
            args,
            command="run",
            robot=snake.robot,
            backend=snake.backend,
            rate_hz=args.rate,
            gait={"gait": gait_facts(gait_name, gait, {}), "duration_s": args.duration},
        )
        log = telemetry.log
        with flag_errors():
            stack.enter_context(snake)
        for estimator in observers:  # a pose before the first cycle's gait asks for one
            estimator.start(snake.read_state())
        hooks = _cycle_hooks(stack, snake.backend, args)
        cycle_observers: list[Callable[[CycleRecord], None]] = (
            [] if compliance is None else [compliance.observe]
        )
        summary = snake.run(
            gait,
            duration_s=args.duration,
            rate_hz=args.rate,
            log=log,
            on_cycle=_chain(hooks) if hooks else None,
            observers=[*observers, *cycle_observers],
            stop=None if steering is None else steering.reached,
        )
    goal = {} if steering is None else steering_summary(steering)
    if compliance is not None:
        goal["compliance"] = compliance.summary()
    if args.torque_limit is not None:
        goal["torque_limit_nm"] = args.torque_limit
    summary = replace(
        summary,
        gait=gait_name,
        video=str(args.video) if args.video else None,
        log=str(args.log) if args.log else None,
        extra={**summary.extra, **telemetry.summary, **goal},
    )
    if args.json:
        print_json(summary.to_dict())
    else:
        print_summary(summary)
    return 130 if summary.interrupted else 0


def _cycle_hooks(
    stack: contextlib.ExitStack, backend: Backend, args: argparse.Namespace
) -> list[Any]:
    hooks: list[Any] = []
    if args.video or args.viewer:
        if not isinstance(backend, Simulated):
            raise ConfigError(
                "--video" if args.video else "--viewer",
                "",
                f"{type(backend).__name__} has no MuJoCo model to render",
            )
        if args.video:
            hooks.append(stack.enter_context(VideoOutput(backend, args.video, args.rate)))
        if args.viewer:
            from snakebot.backends.twin.viewer import PassiveViewer

            hooks.append(stack.enter_context(PassiveViewer(backend)))
    if not args.json and sys.stderr.isatty() and (args.duration >= 5 or args.video):
        hooks.append(ProgressLine(args.duration))
    return hooks


VIDEO_SUFFIXES = (".mp4", ".mkv", ".mov", ".webm", ".avi")


class VideoOutput:
    """The twin's VideoRecorder, its failures (the encoder, the file, offscreen rendering) as
    OutputError naming the file."""

    def __init__(self, backend: Simulated, path: Path, rate_hz: float) -> None:
        from snakebot.backends.twin.video import VideoRecorder

        self.path = path
        platform = os.environ.get("MUJOCO_GL") or "the default OpenGL platform"
        print(f"snakebot: rendering {path} offscreen ({platform})", file=sys.stderr, flush=True)
        with self._failures("cannot record the video"):
            self._recorder = VideoRecorder(backend, path, rate_hz)

    @contextlib.contextmanager
    def _failures(self, what: str) -> Iterator[None]:
        import mujoco

        try:
            yield
        except (OSError, ValueError, RuntimeError) as exc:  # imageio / ffmpeg: format, pipe, disk
            raise OutputError(self.path, f"{what}: {exc}") from exc
        except mujoco.FatalError as exc:
            raise OutputError(
                self.path,
                f"{what}: no offscreen rendering ({exc}); on a machine without a "
                "display install Mesa's EGL (libegl1) or OSMesa (libosmesa6), or set "
                "MUJOCO_GL=egl (or osmesa) before anything imports mujoco",
            ) from exc

    def __call__(self, cycle: int, gait_time_s: float) -> None:
        """Render and encode a frame when one is due."""
        with self._failures("cannot write the video"):
            self._recorder(cycle, gait_time_s)

    def __enter__(self) -> VideoOutput:
        return self

    def __exit__(self, *exc_info: object) -> None:
        with self._failures("cannot finish the video"):
            self._recorder.__exit__(None, None, None)
        print(f"snakebot: wrote {self._recorder.frames} frames to {self.path}", file=sys.stderr)


def _chain(hooks: list[Any]) -> Any:
    def on_cycle(cycle: int, gait_time_s: float) -> None:
        for hook in hooks:
            hook(cycle, gait_time_s)

    return on_cycle


class ProgressLine:
    """A one-line progress display on stderr, refreshed a few times a second."""

    def __init__(self, duration_s: float) -> None:
        self.duration_s = duration_s
        self._next = 0.0

    def __call__(self, cycle: int, gait_time_s: float) -> None:
        """Redraw the bar if a quarter second has passed."""
        now = time.monotonic()
        if now < self._next:
            return
        self._next = now + 0.25
        fraction = min(gait_time_s / self.duration_s, 1.0)
        bar = "#" * int(fraction * 30)
        sys.stderr.write(f"\r  [{bar:<30}] {gait_time_s:6.1f}/{self.duration_s:g} s")
        if fraction >= 1.0:
            sys.stderr.write("\n")
        sys.stderr.flush()


def print_summary(run: RunSummary) -> None:
    """A readable summary of a run."""
    summary = run.to_dict()

    def fmt(key: str, unit: str = "", digits: int = 3) -> str:
        value = summary.get(key)
        if value is None:
            return "n/a"
        if isinstance(value, float):
            return f"{value:.{digits}f}{unit}"
        return f"{value}{unit}"

    lines = [
        f"{summary['robot']} / {summary['gait']} on {summary['backend']}"
        + ("  (interrupted: ramped out early)" if run.interrupted else ""),
        f"  time         {fmt('duration_s', ' s', 2)}, {fmt('control_cycles')} control cycles at "
        f"{fmt('achieved_rate_hz', ' Hz', 1)} ({fmt('overruns')} overruns)",
        f"  distance     {fmt('distance_m', ' m')} at heading {fmt('heading_deg', ' deg', 1)} "
        f"({fmt('speed_mps', ' m/s')})",
        f"  per cycle    {fmt('body_lengths_per_cycle', ' body lengths')} over "
        f"{fmt('cycles', ' gait cycles', 2)}",
        f"  tracking     {fmt('tracking_rms_rad', ' rad RMS', 4)}; max command "
        f"{fmt('max_abs_command_rad', ' rad')}",
        f"  efficiency   cost of transport {fmt('cost_of_transport')}",
    ]
    physics = summary.get("physics")
    if isinstance(physics, dict):
        lines.append(physics_line(physics))
    if "log" in summary:
        lines.append(f"  log          {summary['log']} ({run.log_rows} rows)")
    if "video" in summary:
        lines.append(f"  video        {summary['video']}")
    print("\n".join(lines))
    if isinstance(physics, dict):
        for warning in physics.get("warnings", []):
            print(f"warning: physics: {warning} (docs/physics.md)", file=sys.stderr)


def physics_line(physics: dict[str, object]) -> str:
    """One summary line of the twin's physics health."""
    return (
        f"  physics      penetration {physics['max_floor_penetration_mm']:.1f} mm floor, "
        f"{physics['max_self_penetration_mm']:.1f} mm self; airborne "
        f"{physics['airborne_fraction']:.0%}, upside down {physics['upside_down_fraction']:.0%}, "
        f"chatter {physics['chatter']:.0%}, stall {physics['longest_stall_s']:.1f} s, "
        f"{len(physics['warnings'])} warnings"  # type: ignore[arg-type]
    )
