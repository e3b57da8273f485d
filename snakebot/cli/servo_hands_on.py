"""``snakebot servo torque off|on`` and ``snakebot servo jog ID ANGLE``: hands-on servo tools."""

from __future__ import annotations

import argparse
import dataclasses
import math
import re
import sys
from typing import Any

from snakebot.cli.common import add_dry_run, print_json, report_dry_run, robot_name
from snakebot.cli.console import confirm
from snakebot.config import load_robot
from snakebot.errors import BusError
from snakebot.setup import Link, SetupError, load_settings
from snakebot.setup.hands_on import (
    JOG_SPEED_RAD_S,
    check_jog,
    jog,
    read_states,
    set_torque,
    torque_on_refusals,
)

_ANGLE = re.compile(r"^\s*([+-]?(?:\d+\.?\d*|\.\d+))\s*(deg|°|rad)?\s*$")


def angle_arg(text: str) -> float:
    """An angle in degrees (``15``, ``-15``, ``15deg``) or radians (``0.26rad``), as radians."""
    match = _ANGLE.match(text)
    if match is None:
        raise argparse.ArgumentTypeError(
            f"expected an angle in degrees (15, -15, 15deg) or radians (0.26rad), got {text!r}"
        )
    value = float(match.group(1))
    return value if match.group(2) == "rad" else math.radians(value)


def speed_arg(text: str) -> float:
    """A positive speed in deg/s, as rad/s."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not value > 0.0 or math.isinf(value):
        raise argparse.ArgumentTypeError(f"expected a positive speed in deg/s, got {text!r}")
    return math.radians(value)


def add_actions(actions: Any, port: Any, servo_id_arg: Any) -> None:
    """Register ``torque`` and ``jog`` under ``servo`` (``port`` adds --robot/--port/--baud)."""
    torque = actions.add_parser(
        "torque",
        help="torque off (joints go limp) or on (hold where they stand)",
        description="off: the joints go limp (support the snake first; asks when a servo holds "
        "torque). on: every joint holds where it stands now (nothing jumps).",
    )
    torque.add_argument("torque", choices=("off", "on"), help="off: limp; on: hold")
    port(torque)
    which = torque.add_mutually_exclusive_group()
    which.add_argument("--id", type=servo_id_arg, help="one servo (default: the robot's servos)")
    which.add_argument("--all", action="store_true", help="every servo that answers")
    torque.add_argument("--yes", action="store_true", help="do not ask before going limp")
    add_dry_run(torque, "no torque changes")
    torque.add_argument("--json", action="store_true", help="print one JSON object")
    torque.set_defaults(handler=run_torque, writes=True)

    move = actions.add_parser(
        "jog",
        help="move one joint slowly to an angle, then hold it there",
        description="Move the joint of servo ID from where it stands to ANGLE (the joint angle "
        "of the robot file: direction and zero offset applied; degrees, or radians with a 'rad' "
        "suffix) at --speed, then hold it there (torque on; `snakebot servo torque off` goes "
        "limp). Refuses angles outside the joint's lower_rad..upper_rad.",
    )
    move.add_argument("id", metavar="ID", type=servo_id_arg, help="the servo to move")
    move.add_argument(
        "angle",
        metavar="ANGLE",
        type=angle_arg,
        help="joint angle: 15, -15, 15deg, 0.26rad (a negative one with a unit goes after --)",
    )
    port(move)
    move.add_argument(
        "--speed",
        type=speed_arg,
        default=JOG_SPEED_RAD_S,
        metavar="DEG_S",
        help=f"deg/s (default {math.degrees(JOG_SPEED_RAD_S):g}; at most the "
        "robot's joint speed limit)",
    )
    add_dry_run(move, "nothing moves")
    move.add_argument("--json", action="store_true", help="print one JSON object")
    move.set_defaults(handler=run_jog, writes=True)


def run_torque(args: argparse.Namespace) -> int:
    """Turn torque off or on; going limp asks first when a servo holds torque."""
    robot = load_robot(robot_name(args, hardware=True, what="servo torque"))
    args.port = args.port or robot.bus.port
    args.baud = args.baud or robot.bus.baud
    on = args.torque == "on"
    with Link(args.port, args.baud, model=robot.servo.name, protocol=robot.bus.protocol) as link:
        if args.all:
            ids = sorted(link.listening(args.baud))
            if not ids:
                raise BusError(args.port, [], f"no servo answered at {args.baud} baud")
        else:
            ids = [args.id] if args.id is not None else list(robot.servo_ids)
        states = read_states(link, ids, args.baud)
        holding = [s.servo_id for s in states if s.torque_on]
        if on:
            problems = torque_on_refusals(states)
            if problems:
                raise SetupError("torque stays off:\n  - " + "\n  - ".join(problems))
        if args.dry_run:
            return report_dry_run(
                args,
                {"port": args.port, "torque": args.torque, "ids": ids, "holding_torque": holding},
            )
        if not on and holding:
            print(
                f"WARNING: servo(s) {', '.join(map(str, holding))} hold torque; their joints "
                "go limp: support the snake or lay it down",
                file=sys.stderr,
            )
            confirm("Turn torque off?", assume_yes=args.yes, what="servo torque off")
        set_torque(link, ids, args.baud, on=on)
    if args.json:
        print_json({"port": args.port, "torque": args.torque, "ids": ids})
    else:
        done = "holds where it stands" if on else "is limp"
        for servo_id in ids:
            print(f"servo {servo_id}: torque {args.torque}; {done}")
    return 0


def run_jog(args: argparse.Namespace) -> int:
    """Move one joint to ANGLE at --speed and hold it there."""
    robot = load_robot(robot_name(args, hardware=True, what="servo jog"))
    joints = {j.servo_id: i for i, j in enumerate(robot.joints)}
    if args.id not in joints:
        raise SetupError(
            f"{robot.source}: no joint has servo_id {args.id} (the robot's servos: "
            f"{', '.join(map(str, robot.servo_ids))})"
        )
    joint = joints[args.id]
    chain = load_settings(robot)
    check_jog(chain, joint, args.angle, args.speed)
    args.port = args.port or robot.bus.port
    if args.baud is not None and args.baud != chain.baud:
        chain = dataclasses.replace(chain, baud=args.baud)
    with Link(args.port, chain.baud, model=robot.servo.name, protocol=robot.bus.protocol) as link:
        if args.dry_run:
            (state,) = read_states(link, [args.id], chain.baud)
            return report_dry_run(
                args,
                {
                    "port": args.port,
                    "id": args.id,
                    "joint": joint,
                    "target_deg": round(math.degrees(args.angle), 2),
                    "speed_deg_s": round(math.degrees(args.speed), 1),
                    "present_ticks": state.present_ticks,
                    "torque_on": state.torque_on,
                },
            )
        result = jog(link, chain, joint, args.angle, speed_rad_s=args.speed)
    summary = {
        "port": args.port,
        "id": result.servo_id,
        "joint": result.joint,
        "start_deg": round(math.degrees(result.start_rad), 2),
        "target_deg": round(math.degrees(result.target_rad), 2),
        "end_deg": round(math.degrees(result.end_rad), 2),
        "seconds": round(result.seconds, 2),
        "torque": "on",
    }
    if args.json:
        print_json(summary)
    else:
        print(
            f"servo {result.servo_id} (joint {result.joint}): {summary['start_deg']:+.1f} -> "
            f"{summary['end_deg']:+.1f} deg in {result.seconds:.1f} s; holds there (`snakebot "
            "servo torque off` goes limp)"
        )
    return 0
