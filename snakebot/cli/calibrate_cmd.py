"""``snakebot calibrate``: zero offsets from the snake laid straight, into the robot file."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from snakebot.cli.common import (
    add_bus_options,
    add_force_option,
    add_robot_option,
    check_robot_copy,
    copy_for_write,
    positive_float,
    print_json,
    robot_name,
    robot_write_target,
)
from snakebot.cli.console import confirm
from snakebot.config import load_robot
from snakebot.config.schema import RobotConfig
from snakebot.errors import UsageError
from snakebot.setup import Link, SetupError, load_settings
from snakebot.setup.calibrate import (
    MAX_OFFSET_DEG,
    JointZero,
    measure,
    refusals,
    write_homing_offsets,
    write_offsets,
    zeroes_servo,
)


def add_parser(subparsers: Any) -> None:
    """Register the ``calibrate`` command."""
    parser = subparsers.add_parser(
        "calibrate",
        help="measure zero offsets with the snake laid straight",
        description="Lay the snake straight (torque off), then run this: it reads every servo's "
        "position, shows the zero offsets and, once you confirm, writes them into the robot file "
        "(joints[].zero_offset_rad; comments and layout kept). On Dynamixel the servos' Homing "
        "Offset stays 0; on Feetech STS it is written into each servo (EEPROM unlocked, written, "
        "locked again) so a straight joint reads the centre tick.",
    )
    add_robot_option(parser, hardware="always")
    add_bus_options(parser, baud=False)  # the rate comes from the robot's settings
    parser.add_argument(
        "--max-offset-deg",
        type=positive_float,
        default=MAX_OFFSET_DEG,
        help=f"refuse offsets beyond this (default {MAX_OFFSET_DEG:g})",
    )
    parser.add_argument("--dry-run", action="store_true", help="show the offsets, write nothing")
    parser.add_argument(
        "--out",
        type=Path,
        metavar="FILE",
        help="write a copy of the robot file with the new offsets here",
    )
    add_force_option(parser)
    parser.add_argument("--yes", action="store_true", help="write without asking")
    parser.add_argument("--json", action="store_true", help="print the offsets as JSON")
    parser.set_defaults(handler=run, writes=True)


def run(args: argparse.Namespace) -> int:
    """Measure, show, check, confirm, write."""
    robot = load_robot(robot_name(args, hardware=True, what="calibrate"))
    target = robot_write_target(args, robot.source, "the zero offsets")
    if target is None and not args.dry_run:
        raise UsageError(
            "calibrate writes the zero offsets into a robot file: name it by path "
            "(--robot FILE.toml) or give --out FILE; a robot named by name may be a file "
            "installed with snakebot, which it never writes"
        )
    check_robot_copy(args, robot.source)
    chain = load_settings(robot)
    port = args.port or robot.bus.port
    with Link(port, chain.baud, model=robot.servo.name, protocol=robot.bus.protocol) as link:
        zeros = measure(link, chain)
        problems = refusals(chain, zeros, args.max_offset_deg)
        _show(args, robot, zeros, problems, in_servo=zeroes_servo(link))
        if problems:
            raise SetupError(
                "calibration refused, nothing written:\n  - " + "\n  - ".join(problems)
            )
        if args.dry_run:
            print("dry run: nothing written")
            return 0
        assert target is not None
        confirm(f"Write these offsets into {target}?", assume_yes=args.yes, what="calibrate")
        copy_for_write(robot.source, target)
        if zeroes_servo(link):
            write_homing_offsets(link, chain, zeros)
            print(f"wrote {len(zeros)} Homing Offsets into the servos (EEPROM, locked again)")
    write_offsets(robot, zeros, path=target)
    print(f"wrote {len(zeros)} zero offsets into {target} (joints[].zero_offset_rad)")
    return 0


def _show(
    args: argparse.Namespace,
    robot: RobotConfig,
    zeros: list[JointZero],
    problems: list[str],
    *,
    in_servo: bool,
) -> None:
    if args.json:
        print_json(
            {
                "robot": robot.name,
                "file": str(robot.source),
                "joints": [
                    {
                        "joint": z.joint,
                        "id": z.servo_id,
                        "present_ticks": z.present_ticks,
                        "old_offset_rad": z.old_offset_rad,
                        "new_offset_rad": round(z.new_offset_rad, 4),
                        "actual_ticks": z.actual_ticks,
                        "old_homing_offset": z.old_homing_offset,
                        "homing_offset": z.homing_offset,
                    }
                    for z in zeros
                ],
                "problems": problems,
            }
        )
        return
    homing = f"  {'homing offset':>15}" if in_servo else ""
    print(f"{'joint':>5}  {'ID':>3}  {'ticks':>6}{homing}  {'old offset':>12}  {'new offset':>22}")
    for z in zeros:
        moved = f"  {z.old_homing_offset:>6} -> {z.homing_offset:<5}" if in_servo else ""
        print(
            f"{z.joint:>5}  {z.servo_id:>3}  {z.present_ticks:>6}{moved}  "
            f"{math.degrees(z.old_offset_rad):>8.2f} deg  {z.new_offset_rad:>9.4f} rad "
            f"({math.degrees(z.new_offset_rad):+6.2f} deg)"
        )
