"""``snakebot run``: play a gait on the twin or the servo chain and summarise the run."""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from types import FrameType
from typing import Any

from snakebot.backends.base import Backend
from snakebot.cli.common import (
    RATE_HZ,
    add_robot_option,
    check_writable,
    port_arg,
    positive_float,
    print_json,
    robot_name,
)
from snakebot.config import RobotConfig
from snakebot.config.body import BodyConfig
from snakebot.config.body_loader import load_robot_or_body
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, RunResult, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.errors import ConfigError, OutputError, UsageError
from snakebot.gaits import Gait, load_gait_file, make_gait, parse_set_options
from snakebot.telemetry import CsvTelemetryWriter


def add_parser(subparsers: Any) -> None:
    """Register the ``run`` command."""
    parser = subparsers.add_parser("run", help="run a gait on the twin (default) or the robot")
    add_robot_option(parser, hardware="with --backend dynamixel")
    parser.add_argument("--gait", help="gait name (see `snakebot gaits`; default serpenoid)")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a gait parameter (repeatable), e.g. --set omega=pi",
    )
    parser.add_argument("--gait-file", type=Path, help="replay a saved gait (TOML)")
    parser.add_argument("--policy", metavar="DIR", help="play a trained policy (`snakebot rl "
                        "train`) as the gait; needs snakebot[rl]")
    parser.add_argument("--command", metavar="A,B", help="with --policy: speed,turn_rate (m/s, "
                        "rad/s) for a velocity policy; goal X,Y (m, X ahead) for a goal policy")
    parser.add_argument(
        "--backend",
        choices=("sim", "dynamixel"),
        default="sim",
        help="sim: the MuJoCo twin (default); dynamixel: the servo chain",
    )
    parser.add_argument(
        "--duration",
        type=positive_float,
        default=10.0,
        help="gait time in seconds, before the ramp-out (default 10)",
    )
    parser.add_argument(
        "--rate", type=RATE_HZ, default=100.0, help="control rate in Hz (default 100)"
    )
    parser.add_argument(
        "--friction",
        metavar="AXIAL,LATERAL",
        help="twin ground friction along and across each module; "
        "equal values = isotropic (overrides the robot's ground model); "
        "one number MU for a mass-spring body's floor",
    )
    parser.add_argument(
        "--directional",
        choices=("on", "off"),
        help="mass-spring bodies: Miller's directional friction on or off (default: the body file)",
    )
    parser.add_argument(
        "--terrain",
        metavar="NAME[:KEY=VALUE,...]",
        help="twin terrain: flat (default) or cliff, e.g. cliff:edge_m=0.1,height_m=0.04",
    )
    parser.add_argument("--realtime", action="store_true", help="pace the twin to the wall clock")
    parser.add_argument(
        "--viewer", action="store_true", help="open MuJoCo's viewer (needs a display)"
    )
    parser.add_argument("--video", type=Path, help="render the twin to an MP4 file (offscreen)")
    parser.add_argument("--log", type=Path, help="per-cycle telemetry CSV")
    parser.add_argument(
        "--port", type=port_arg, help="serial port for --backend dynamixel (default: robot config)"
    )
    parser.add_argument("--baud", type=int, help="baud rate for --backend dynamixel")
    parser.add_argument(
        "--allow-extra-servos",
        action="store_true",
        help="--backend dynamixel: servos on the bus that the robot file does not name are "
        "expected (left alone); without it connect refuses, naming them",
    )
    parser.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    parser.set_defaults(handler=run)


def build_gait(robot: RobotConfig | BodyConfig, args: argparse.Namespace) -> tuple[str, Gait]:
    """The gait from --gait-file and/or --gait, with --set overrides on top."""
    params: dict[str, object] = {}
    name = args.gait or "serpenoid"
    if args.gait_file is not None:
        file_name, params, _meta = load_gait_file(args.gait_file)
        if args.gait and args.gait != file_name:
            raise ConfigError(
                "--gait",
                "",
                f"{args.gait_file} holds gait {file_name!r}, "
                f"not {args.gait!r}; drop --gait or pick the matching file",
            )
        name = file_name
    params.update(parse_set_options(name, args.set))
    gait = make_gait(
        name, robot.joint_count, params, lower_rad=robot.lower_rad, upper_rad=robot.upper_rad
    )
    return name, gait


def make_backend(robot: RobotConfig | BodyConfig, args: argparse.Namespace) -> Backend:
    """The backend --backend names, configured from the options."""
    if isinstance(robot, BodyConfig):
        from snakebot.cli.softbody_options import make_softbody_backend

        return make_softbody_backend(robot, args)
    if args.directional is not None:
        raise ConfigError("--directional", "", "applies to mass-spring bodies only")
    if args.backend == "sim":
        from snakebot.backends.twin import GroundFriction, TwinBackend
        from snakebot.backends.twin.cliff import parse_terrain

        friction = GroundFriction.parse(args.friction) if args.friction else None
        terrain = parse_terrain(args.terrain) if args.terrain else None
        return TwinBackend(
            robot, friction=friction, realtime=args.realtime or args.viewer, terrain=terrain
        )
    if args.viewer or args.video or args.friction or args.terrain:
        raise ConfigError(
            "--backend", "", "--viewer, --video, --friction and --terrain need --backend sim"
        )
    from snakebot.backends.dynamixel import DynamixelBackend

    return DynamixelBackend(
        robot, port=args.port, baud=args.baud, allow_extra_servos=args.allow_extra_servos
    )


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Treat SIGTERM like Ctrl-C so a killed run still ramps out and leaves servos safe."""

    def handler(signum: int, frame: FrameType | None) -> None:
        raise KeyboardInterrupt

    try:
        previous = signal.signal(signal.SIGTERM, handler)
    except ValueError:  # not the main thread
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def run(args: argparse.Namespace) -> int:
    """Load, build, run, summarise; telemetry stays on disk whatever happens."""
    hardware = args.backend == "dynamixel"
    robot = load_robot_or_body(robot_name(args, hardware=hardware, what="run --backend dynamixel"))
    if args.policy is None:
        if args.command is not None:
            raise UsageError("--command goes with --policy (a trained policy's command)")
        gait_name, gait = build_gait(robot, args)
    plan = RunPlan(duration_s=args.duration, rate_hz=args.rate)
    backend = make_backend(robot, args)
    if args.policy is not None:  # a closed-loop gait reads the backend it drives
        from snakebot.rl.cli_policy import policy_gait

        gait_name, gait = policy_gait(robot, backend, args)
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)
    safety = SafetyLayer.for_robot(robot)
    # Outputs open before the backend connects: one that cannot be written stops the run before
    # a servo moves. Written rows stay on disk whatever ends the run.
    if args.video:
        if args.video.suffix.lower() not in VIDEO_SUFFIXES:
            raise ConfigError("--video", str(args.video), "expected a video file name ending in "
                              f"{', '.join(VIDEO_SUFFIXES)}")
        check_writable(args.video, "video")
    with contextlib.ExitStack() as stack:
        log = (
            stack.enter_context(CsvTelemetryWriter(args.log, robot.joint_count))
            if args.log
            else None
        )
        stack.enter_context(sigterm_as_interrupt())
        stack.enter_context(backend)
        hooks = _cycle_hooks(stack, backend, args, plan)
        result = run_gait(
            backend, gait, safety, plan, metrics, log=log, on_cycle=_chain(hooks) if hooks else None
        )
    summary = {"robot": robot.name, "gait": gait_name, "backend": args.backend, **result.summary}
    if isinstance(robot, BodyConfig):
        summary.update(backend.stats.extra)
    if args.log:
        summary["log"] = str(args.log)
    if args.video:
        summary["video"] = str(args.video)
    if args.json:
        print_json(summary)
    else:
        print_summary(summary, result)
    return 130 if result.interrupted else 0


def _cycle_hooks(
    stack: contextlib.ExitStack, backend: Backend, args: argparse.Namespace, plan: RunPlan
) -> list[Any]:
    hooks: list[Any] = []
    from snakebot.backends.softbody import SoftBodyBackend
    from snakebot.backends.twin import TwinBackend

    if isinstance(backend, TwinBackend | SoftBodyBackend) and args.video:
        hooks.append(stack.enter_context(VideoOutput(backend, args.video, plan.rate_hz)))
    if isinstance(backend, TwinBackend | SoftBodyBackend) and args.viewer:
        from snakebot.backends.twin.viewer import PassiveViewer

        hooks.append(stack.enter_context(PassiveViewer(backend)))
    if not args.json and sys.stderr.isatty() and plan.duration_s >= 5:
        hooks.append(ProgressLine(plan))
    return hooks


VIDEO_SUFFIXES = (".mp4", ".mkv", ".mov", ".webm", ".avi")


class VideoOutput:
    """The twin's VideoRecorder, its failures (the encoder, the file, offscreen rendering) as
    OutputError naming the file."""

    def __init__(self, backend: Any, path: Path, rate_hz: float) -> None:
        from snakebot.backends.twin.video import VideoRecorder

        self.path = path
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
                self.path, f"{what}: no offscreen rendering ({exc}); on a machine without a "
                "display set MUJOCO_GL=egl (or osmesa)"
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


def _chain(hooks: list[Any]) -> Any:
    def on_cycle(cycle: int, gait_time_s: float) -> None:
        for hook in hooks:
            hook(cycle, gait_time_s)

    return on_cycle


class ProgressLine:
    """A one-line progress display on stderr, refreshed a few times a second."""

    def __init__(self, plan: RunPlan) -> None:
        self.plan = plan
        self._next = 0.0

    def __call__(self, cycle: int, gait_time_s: float) -> None:
        """Redraw the bar if a quarter second has passed."""
        now = time.monotonic()
        if now < self._next:
            return
        self._next = now + 0.25
        fraction = min(gait_time_s / self.plan.duration_s, 1.0)
        bar = "#" * int(fraction * 30)
        sys.stderr.write(f"\r  [{bar:<30}] {gait_time_s:6.1f}/{self.plan.duration_s:g} s")
        if fraction >= 1.0:
            sys.stderr.write("\n")
        sys.stderr.flush()


def print_summary(summary: dict[str, object], result: RunResult) -> None:
    """A readable summary of a run."""

    def fmt(key: str, unit: str = "", digits: int = 3) -> str:
        value = summary.get(key)
        if value is None:
            return "n/a"
        if isinstance(value, float):
            return f"{value:.{digits}f}{unit}"
        return f"{value}{unit}"

    lines = [
        f"{summary['robot']} / {summary['gait']} on {summary['backend']}"
        + ("  (interrupted: ramped out early)" if result.interrupted else ""),
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
    if "log" in summary:
        lines.append(f"  log          {summary['log']} ({result.log_rows} rows)")
    if "video" in summary:
        lines.append(f"  video        {summary['video']}")
    print("\n".join(lines))
