"""``snakebot emulate``: a virtual servo chain on a pseudo-terminal, with optional twin physics."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from types import FrameType
from typing import Any

from snakebot.cli.common import add_robot_option, print_json
from snakebot.config import load_robot
from snakebot.errors import ConfigError


def add_parser(subparsers: Any) -> None:
    """Register the ``emulate`` command."""
    parser = subparsers.add_parser(
        "emulate",
        help="serve an emulated Dynamixel chain on a pseudo-terminal",
        description="Create a pseudo-terminal that answers like the robot's servo chain (Protocol "
        "2.0, byte for byte). Prints the device path first; serves until Ctrl-C or SIGTERM.",
    )
    add_robot_option(parser)
    parser.add_argument("--baud", type=int, help="line rate (default: the robot's bus.baud)")
    parser.add_argument(
        "--physics",
        action="store_true",
        help="back the servos with the MuJoCo twin in real time; print its summary on exit",
    )
    parser.add_argument("--pty", action="store_true", required=True, help="serve on a pty")
    parser.add_argument("--json", action="store_true", help='print {"port": ...} and JSON summary')
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Serve until SIGINT or SIGTERM, then stop cleanly."""
    from snakebot.emulation import make_chain_for_ids
    from snakebot.emulation.pty_server import PtyServer

    robot = load_robot(args.robot)
    baud = args.baud or robot.bus.baud
    motion = None
    if args.physics:
        from snakebot.emulation.physics import make_twin_chain

        chain, motion = make_twin_chain(robot, baud)
    else:
        try:
            chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud)
        except ValueError as exc:
            raise ConfigError("--baud", "", str(exc)) from exc
    stop = threading.Event()

    def on_signal(signum: int, frame: FrameType | None) -> None:
        stop.set()

    previous = {sig: signal.signal(sig, on_signal) for sig in (signal.SIGINT, signal.SIGTERM)}
    server = PtyServer(chain)
    try:
        server.start()
        if args.json:
            print_json({"port": server.device_path, "baud": baud, "servo_ids": robot.servo_ids})
        else:
            print(server.device_path, flush=True)
            print(
                f"{robot.name}: {robot.joint_count} x {robot.servo.name} (IDs "
                f"{robot.servo_ids[0]}..{robot.servo_ids[-1]}) at {baud} baud"
                + (", twin physics" if motion else "")
                + "; Ctrl-C to stop",
                file=sys.stderr,
                flush=True,
            )
        while not stop.wait(0.2):
            pass
    finally:
        server.stop()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if motion is not None:
            motion.twin.close()
    if motion is not None:
        summary = {"robot": robot.name, "backend": "emulate --physics", **motion.summary()}
        if args.json:
            print_json(summary)
        else:
            print(
                f"twin: moved {summary['distance_m']:.3f} m at heading "
                f"{summary['heading_deg']:.1f} deg in {summary['duration_s']:.1f} s"
            )
    return 0
