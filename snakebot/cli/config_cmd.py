"""``snakebot config diff|apply|assign-id``: servo settings from firmware_configs/, kept in sync."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from snakebot.cli.common import (
    add_bus_options,
    add_dry_run,
    add_robot_option,
    baud_arg,
    print_json,
    robot_name,
)
from snakebot.cli.console import confirm
from snakebot.config import load_robot
from snakebot.setup import Link, Step, apply, assign_id, load_settings, plan_apply, survey
from snakebot.setup.assign import search_bauds
from snakebot.setup.diff import ChainDiff
from snakebot.setup.scan import sweep_seconds


def add_parser(subparsers: Any) -> None:
    """Register ``config`` and its actions."""
    parser = subparsers.add_parser(
        "config",
        help="compare and write servo settings (diff, apply, assign-id)",
        description="Servo settings as data: servos/<model>.toml [settings] plus the robot "
        "file's overrides. Servos are found at any baud rate.",
    )
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    diff = actions.add_parser("diff", help="list settings that differ; exit 1 if any do")
    _robot_and_port(diff)
    diff.add_argument("--json", action="store_true", help="print one JSON object")
    diff.set_defaults(handler=run_diff, writes=False)

    write = actions.add_parser(
        "apply",
        help="write the differences (torque off for EEPROM, baud changes last)",
    )
    _robot_and_port(write)
    write.add_argument("--dry-run", action="store_true", help="print the plan, write nothing")
    write.add_argument("--yes", action="store_true", help="do not ask before torque goes off")
    write.add_argument("--json", action="store_true", help="print one JSON object")
    write.set_defaults(handler=run_apply, writes=True)

    assign = actions.add_parser(
        "assign-id",
        help="give one (factory-fresh) servo its ID and baud rate",
        description="Finds the one servo on the bus at any baud rate (a new one is ID 1 at "
        "57600, an AX at 1000000) and sets its ID and baud rate. Refuses if several servos "
        "answer or the ID is taken. Growing a chain: plug in one new servo at a time and pass "
        "--from 1.",
    )
    _robot_and_port(assign)
    assign.add_argument("--to", type=servo_id_arg, required=True, help="new ID (0..252)")
    assign.add_argument(
        "--from",
        dest="from_id",
        type=servo_id_arg,
        help="only the servo answering as this ID (default: the only servo)",
    )
    assign.add_argument(
        "--new-baud", type=baud_arg, help="baud rate to set (default: the robot's bus.baud)"
    )
    add_dry_run(assign, "the servo keeps its ID and rate")
    assign.add_argument("--json", action="store_true", help="print one JSON object")
    assign.set_defaults(handler=run_assign, writes=True)


def _robot_and_port(parser: argparse.ArgumentParser) -> None:
    add_robot_option(parser, hardware="always")
    add_bus_options(parser, baud=False)  # servos are found at any rate


def servo_id_arg(text: str) -> int:
    """argparse type: a servo ID 0..252."""
    value = int(text) if text.isdigit() else -1
    if not 0 <= value <= 252:
        raise argparse.ArgumentTypeError(f"expected a servo ID 0..252, got {text!r}")
    return value


def _table(diff: ChainDiff) -> list[str]:
    rows = [("ID", "setting", "servo", "wanted", "unit")]
    for d in diff.differences:
        row = d.row()
        rows.append(
            (
                str(d.servo_id),
                d.key,
                str(row["servo_value"]),
                str(row["wanted_value"]),
                str(row["unit"]),
            )
        )
    widths = [max(len(r[i]) for r in rows) for i in range(5)]
    return [
        "  ".join(
            c.rjust(w) if i == 0 else c.ljust(w)
            for i, (c, w) in enumerate(zip(r, widths, strict=True))
        ).rstrip()
        for r in rows
    ]


def run_diff(args: argparse.Namespace) -> int:
    """Print the differences; 0 when none, 1 when some."""
    robot = load_robot(robot_name(args, hardware=True, what="config diff"))
    chain = load_settings(robot)
    port = args.port or robot.bus.port
    with Link(port, chain.baud, model=robot.servo.name, protocol=robot.bus.protocol) as link:
        diff = survey(link, chain)
    if args.json:
        print_json(
            {
                "robot": robot.name,
                "port": port,
                "identical": diff.identical,
                "servos": [
                    {
                        "id": s.servo_id,
                        "baud": s.baud,
                        "torque_on": s.torque_on,
                        "hardware_error": s.hardware_error,
                    }
                    for s in diff.servos.values()
                ],
                "differences": [d.row() for d in diff.differences],
                "notes": list(diff.notes),
            }
        )
    else:
        count = len(robot.servo_ids)
        if diff.identical:
            print(f"{robot.name} on {port}: all {count} servos hold the configured settings")
        else:
            print("\n".join(_table(diff)))
            servos = len({d.servo_id for d in diff.differences})
            print(
                f"{len(diff.differences)} difference(s) on {servos} of {count} servos; "
                f"`snakebot config apply --robot {args.robot} --port {port}` writes them"
            )
        for note in diff.notes:
            print(f"note: {note}", file=sys.stderr)
    return 0 if diff.identical else 1


def run_apply(args: argparse.Namespace) -> int:
    """Plan, confirm, write, verify; the final diff must come out empty."""
    robot = load_robot(robot_name(args, hardware=True, what="config apply"))
    chain = load_settings(robot)
    port = args.port or robot.bus.port
    with Link(port, chain.baud, model=robot.servo.name, protocol=robot.bus.protocol) as link:
        diff = survey(link, chain)
        plan = plan_apply(chain, diff)
        steps = [step.describe() for step in plan.steps]
        if plan.empty or args.dry_run:
            if args.json:
                print_json(
                    {
                        "robot": robot.name,
                        "port": port,
                        "steps": steps,
                        "written": False,
                        "dry_run": args.dry_run,
                    }
                )
            elif plan.empty:
                print(f"{robot.name} on {port}: nothing to write, all servos hold the settings")
            else:
                print(f"plan for {robot.name} on {port} ({len(steps)} steps):")
                print("\n".join(f"  {step}" for step in steps))
                print("dry run: nothing was written")
            return 0
        out = sys.stderr if args.json else sys.stdout
        print(f"plan for {robot.name} on {port} ({len(steps)} steps):", file=out)
        for step in steps:
            print(f"  {step}", file=out)
        if plan.limp:
            ids = ", ".join(map(str, plan.limp))
            print(
                f"WARNING: torque goes off on servo(s) {ids} to write EEPROM settings: those "
                "joints go limp. Lay the snake down or support it.",
                file=sys.stderr,
            )
        confirm("Write these settings?", assume_yes=args.yes, what="config apply")
        total = len(plan.steps)
        done = iter(range(1, total + 1))

        def report(step: Step) -> None:
            print(f"  [{next(done)}/{total}] {step.describe()}", file=out, flush=True)

        apply(link, chain, plan, diff, on_step=report)
    if args.json:
        print_json(
            {"robot": robot.name, "port": port, "steps": steps, "written": True, "dry_run": False}
        )
        return 0
    print(
        "done: every write read back, the final diff is empty; torque is left off "
        "(`snakebot run` turns it on)"
    )
    return 0


def run_assign(args: argparse.Namespace) -> int:
    """Find the lone servo, set its ID and baud rate, verify."""
    robot = load_robot(robot_name(args, hardware=True, what="config assign-id"))
    baud = args.new_baud or robot.bus.baud
    port = args.port or robot.bus.port
    where = f"ID {args.from_id}" if args.from_id is not None else "the servo"
    with Link(port, baud, model=robot.servo.name, protocol=robot.bus.protocol) as link:
        bauds = search_bauds(link)
        print(
            f"searching for {where} at {', '.join(map(str, bauds))} baud ...",
            file=sys.stderr,
            flush=True,
        )
        family = link.family
        if args.from_id is None and not family.broadcast_ping:
            ids = family.max_id + 1
            print(
                f"{family.label} has no broadcast ping: every ID is pinged on "
                f"its own, {ids} IDs at each rate (about "
                f"{sum(sweep_seconds(ids, b) for b in bauds):.0f} s on a real port; --from 1 "
                "finds a new servo at once)",
                file=sys.stderr,
                flush=True,
            )
        result = assign_id(
            link, to_id=args.to, baud=baud, from_id=args.from_id, bauds=bauds, dry_run=args.dry_run
        )
    found = result.found
    if args.json:
        print_json(
            {
                "port": port,
                "found_id": found.servo_id,
                "found_baud": found.baud,
                "id": result.servo_id,
                "baud": result.baud,
                "written": result.changed and not args.dry_run,
                "dry_run": args.dry_run,
            }
        )
    elif args.dry_run:
        print(
            f"dry run: servo ID {found.servo_id} at {found.baud} baud would become ID "
            f"{result.servo_id} at {result.baud} baud; nothing was written"
        )
    elif not result.changed:
        print(f"servo is already ID {found.servo_id} at {found.baud} baud; nothing written")
    else:
        print(
            f"servo ID {found.servo_id} at {found.baud} baud is now ID {result.servo_id} at "
            f"{result.baud} baud"
        )
    return 0
