"""``snakebot ros2``: serve the twin or the robot as a ROS 2 node (the ``ros2`` extra)."""

from __future__ import annotations

import argparse
import contextlib
import os
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
    add_dry_run,
    add_force_option,
    add_robot_option,
    check_writable,
    print_json,
    report_dry_run,
    robot_name,
)
from snakebot.cli.gait_options import add_gait_options, gait_choices
from snakebot.config import load_robot
from snakebot.drive.setup import SPATIAL_GAITS
from snakebot.drive.signals import StopSignals
from snakebot.errors import SnakebotError
from snakebot.ros2.topics import DEFAULT_COMMAND_TIMEOUT_S, NODE_NAME
from snakebot.session import Snake, watched

BACKEND_OPTIONS = ("port", "baud", "allow_extra_servos", "friction")
"""The backend option flags ``ros2`` offers (the twin always runs in real time here)."""


class CommandTimeoutError(SnakebotError):
    """The node stopped because commands stopped arriving (``--on-timeout stop``)."""


def add_parser(subparsers: Any) -> None:
    """Register the ``ros2`` command."""
    parser = subparsers.add_parser(
        "ros2",
        help="serve the twin (default) or the robot as a ROS 2 node (extra: snakebot[ros2])",
        description="Serve a snake as a ROS 2 node: joint_states, diagnostics, run_metrics and "
        "(on the twin) body_pose out; cmd_vel, joint_commands and joint_trajectory in, every "
        "command through the safety layer. The gait parameter selects the gait cmd_vel steers. "
        "Ctrl-C or SIGTERM: rest pose, then the robot's stop policy. docs/ros2.md has the "
        "topics, QoS and a launch example.",
    )
    add_robot_option(parser, hardware="with --backend dynamixel")
    add_backend_argument(parser)
    add_option_flags(
        parser,
        BACKEND_OPTIONS,
        helps={
            "port": "serial port for --backend dynamixel (default: robot)",
            "baud": "baud rate for --backend dynamixel",
            "allow_extra_servos": "--backend dynamixel: servos on the bus that the robot file "
            "does not name are expected (left alone)",
            "friction": "twin ground friction along and across each module",
        },
    )
    add_gait_options(
        parser,
        gaits_help="comma-separated gaits; the first is the one cmd_vel steers at the start "
        f"(default: serpenoid on all-yaw robots, {SPATIAL_GAITS[0]} on yaw/pitch ones)",
    )
    parser.add_argument(
        "--command-timeout",
        type=float,
        default=DEFAULT_COMMAND_TIMEOUT_S,
        metavar="S",
        help="seconds without a command before --on-timeout acts, counted from the first "
        f"command (default {DEFAULT_COMMAND_TIMEOUT_S:g}; 0: never)",
    )
    parser.add_argument(
        "--on-timeout",
        choices=("stop", "halt"),
        default="stop",
        help="stop: rest pose, then the stop policy, and the node ends (exit 1); halt: speed "
        "and turn to 0, joint targets held, the node serves on (default stop)",
    )
    parser.add_argument("--node-name", default=NODE_NAME, help=f"default {NODE_NAME}")
    parser.add_argument(
        "--loopback",
        action="store_true",
        help="keep DDS on this machine: localhost discovery, Fast DDS on 127.0.0.1 only",
    )
    parser.add_argument(
        "--ros-args",
        nargs=argparse.REMAINDER,
        default=[],
        help="the rest goes to rclpy as --ros-args (remaps, -p parameters, namespace)",
    )
    parser.add_argument(
        "--mcap",
        type=Path,
        metavar="FILE",
        help="also record every cycle to FILE as ROS 2 messages, as run --mcap-encoding ros2 "
        "does (extra: snakebot[ros2-mcap]; docs/ros2.md)",
    )
    add_force_option(parser)
    parser.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    add_dry_run(parser, "no node starts, no servo moves, no recording")
    parser.set_defaults(handler=run, writes=True)


def run(args: argparse.Namespace) -> int:
    """Load, connect, serve until a stop, summarise; servos end as the stop policy says."""
    from snakebot.ros2 import NodeOptions, loopback_environment, require_rclpy

    spec = backend_spec(args)
    robot = load_robot(
        robot_name(args, hardware=spec.hardware, what=f"ros2 --backend {args.backend}")
    )
    options = NodeOptions(
        rate_hz=args.rate,
        command_timeout_s=args.command_timeout,
        on_timeout=args.on_timeout,
        gaits=tuple(gait_choices(robot, args)),
        smoothing_s=args.smoothing,
        transition_s=args.transition,
        node_name=args.node_name,
        ros_args=("--ros-args", *args.ros_args) if args.ros_args else (),
    )
    if args.loopback:  # before rclpy loads: the middleware reads these once
        os.environ.update(loopback_environment())
    if args.mcap is not None:  # the output rule first: an existing file is named, whatever else
        check_writable(args.mcap, "MCAP file", force=args.force)
    require_rclpy()  # the extra, before anything connects
    if args.mcap is not None:
        from snakebot.telemetry.ros2_mcap import mcap_writer_module

        mcap_writer_module()  # the recording's extra too
    from snakebot.ros2.node import run_node

    # ROS clients live on the wall clock: the twin is paced to it.
    given = watched(spec, given_options(args, spec, BACKEND_OPTIONS))
    with flag_errors():
        snake = Snake.prepare(robot, spec, **given)
    snake.backend.check_rate(args.rate)  # refused before the port opens (exit 2)
    if args.dry_run:
        plan = {"robot": robot.name, "backend": spec.name, "rate_hz": args.rate}
        return report_dry_run(args, {**plan, "mcap": args.mcap})
    with contextlib.ExitStack() as stack:
        signals = stack.enter_context(StopSignals())
        recording = []
        if args.mcap is not None:
            from snakebot.cli.telemetry_options import open_ros2_mcap

            gaits = [{"gait": c.name, "params": c.params} for c in options.gait_choices(robot)]
            recording.append(
                open_ros2_mcap(
                    stack, args, robot, snake.backend, args.rate, "ros2", {"gaits": gaits}
                )
            )
        with flag_errors():
            stack.enter_context(snake)
        result = run_node(snake, options, stop_check=signals, observers=recording)
    summary = {"robot": robot.name, "backend": spec.name, **result.summary}
    if args.mcap is not None:
        summary["mcap"] = str(args.mcap)
    if args.json:
        print_json(summary)
    else:
        print(
            f"{robot.name} served on {spec.name}: stopped by {result.stopped_by}; "
            f"{result.cycles} cycles at {summary['achieved_rate_hz']:.1f} Hz, "
            f"{summary['commands']} commands ({summary['refused_commands']} refused)"
        )
    stopped = f"the snake was stopped ({robot.safety.stop_policy} at the rest pose)"
    if result.stopped_by.startswith("interrupted"):
        return 130
    if result.stopped_by.startswith("no command"):
        raise CommandTimeoutError(f"{result.stopped_by}; {stopped}")
    return 0
