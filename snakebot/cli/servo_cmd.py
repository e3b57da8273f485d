"""``snakebot servo reboot|reset|info|models|torque|jog``: recover, inspect and move servos."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from snakebot.backends.chain.faults import decode_hardware_error
from snakebot.cli.common import (
    add_bus_options,
    add_dry_run,
    add_robot_option,
    print_json,
    report_dry_run,
    robot_name,
)
from snakebot.cli.config_cmd import servo_id_arg
from snakebot.cli.console import confirm
from snakebot.cli.servo_hands_on import add_actions
from snakebot.config import load_robot
from snakebot.errors import BusError, UsageError
from snakebot.servo import FACTORY_ID
from snakebot.servo_tables import model_dirs, model_entries, table_for_model
from snakebot.servo_tables.units import display
from snakebot.setup import Link, SetupError
from snakebot.setup.bauds import factory_baud
from snakebot.setup.maintenance import (
    check_reboot,
    factory_reset,
    hardware_error,
    reboot,
    reset_families,
    reset_option,
    servo_info,
)


def add_parser(subparsers: Any) -> None:
    """Register ``servo`` and its actions."""
    parser = subparsers.add_parser(
        "servo", help="reboot, factory-reset, inspect, go limp or jog servos"
    )
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)

    boot = actions.add_parser("reboot", help="reboot servos (clears a latched hardware error)")
    _port(boot)
    which = boot.add_mutually_exclusive_group(required=True)
    which.add_argument("--id", type=servo_id_arg, help="the servo to reboot")
    which.add_argument("--all", action="store_true", help="every servo that answers")
    boot.add_argument("--yes", action="store_true", help="do not ask when a servo holds torque")
    add_dry_run(boot, "no servo reboots")
    boot.add_argument("--json", action="store_true", help="print one JSON object")
    boot.set_defaults(handler=run_reboot, writes=True)

    reset = actions.add_parser("reset", help="factory-reset one servo (erases its settings)")
    _port(reset)
    reset.add_argument("--id", type=servo_id_arg, required=True, help="the servo to reset")
    reset.add_argument("--keep-id", action="store_true", help="keep its ID")
    reset.add_argument("--keep-baud", action="store_true", help="keep its baud (needs --keep-id)")
    reset.add_argument("--yes", action="store_true", help="required: confirms the erase")
    add_dry_run(reset, "the servo keeps its settings")
    reset.add_argument("--json", action="store_true", help="print one JSON object")
    reset.set_defaults(handler=run_reset, writes=True)

    info = actions.add_parser("info", help="model, firmware, errors and the whole control table")
    _port(info)
    info.add_argument("--id", type=servo_id_arg, required=True, help="the servo to read")
    info.add_argument("--json", action="store_true", help="print one JSON object")
    info.set_defaults(handler=run_info, writes=False)
    listing = actions.add_parser(
        "models", help="servo models with control-table data (shipped and SNAKEBOT_SERVO_DATA)"
    )
    listing.add_argument("--json", action="store_true", help="print one JSON object")
    listing.set_defaults(handler=run_models, writes=False)
    add_actions(actions, _port, servo_id_arg)


def _port(parser: argparse.ArgumentParser) -> None:
    add_robot_option(parser, hardware="always")
    add_bus_options(parser)


def _link(args: argparse.Namespace, what: str) -> Link:
    """The robot's port at its baud rate (or --port/--baud), in its servo model's table; sets
    ``args.port`` and ``args.baud`` to what it opens."""
    robot = load_robot(robot_name(args, hardware=True, what=f"servo {what}"))
    args.port = args.port or robot.bus.port
    args.baud = args.baud or robot.bus.baud
    return Link(args.port, args.baud, model=robot.servo.name, protocol=robot.bus.protocol)


def run_reboot(args: argparse.Namespace) -> int:
    """Reboot one servo or all; exit 1 if a hardware error stays latched."""
    with _link(args, "reboot") as link:
        bus = link.bus
        check_reboot(link, args.id)
        ids = sorted(link.listening(args.baud)) if args.all else [args.id]
        if not ids:
            raise BusError(args.port, [], f"no servo answered at {args.baud} baud")
        before = {
            i: {
                "torque_enable": bus.read(i, "torque_enable"),
                "hardware_error_status": hardware_error(link, i, args.baud),
            }
            for i in ids
        }
        holding = [i for i, v in before.items() if v["torque_enable"]]
        if args.dry_run:
            return report_dry_run(
                args,
                {
                    "port": args.port,
                    "baud": args.baud,
                    "reboot": ids,
                    "holding_torque": holding,
                    "latched": {
                        i: decode_hardware_error(v["hardware_error_status"])
                        for i, v in before.items()
                    },
                },
            )
        if holding:
            print(
                f"WARNING: servo(s) {', '.join(map(str, holding))} hold torque; a reboot turns "
                "it off and the joints go limp",
                file=sys.stderr,
            )
            confirm("Reboot anyway?", assume_yes=args.yes, what="servo reboot")
        stuck = []
        rebooted = []
        for servo_id in ids:
            was = decode_hardware_error(before[servo_id]["hardware_error_status"])
            now = decode_hardware_error(reboot(link, servo_id, args.baud))
            status = f"cleared {', '.join(was)}" if was else "no error was latched"
            if now:
                status = f"still latched: {', '.join(now)} (the cause persists)"
                stuck.append(servo_id)
            rebooted.append({"id": servo_id, "was": list(was), "now": list(now)})
            if not args.json:
                print(f"servo {servo_id}: rebooted; {status}")
    if args.json:
        print_json({"port": args.port, "baud": args.baud, "servos": rebooted, "stuck": stuck})
    if stuck:
        print(
            f"snakebot: servo(s) {', '.join(map(str, stuck))} latch their error again: remove "
            "the cause (voltage, heat, a jammed joint) and reboot again",
            file=sys.stderr,
        )
        return 1
    return 0


def run_reset(args: argparse.Namespace) -> int:
    """Factory-reset one servo after checking it will not collide with another."""
    if args.keep_baud and not args.keep_id:
        raise UsageError(
            "the firmware keeps the baud rate only together with the ID (Factory "
            "Reset option 0x02): add --keep-id, or drop --keep-baud"
        )
    link = _link(args, "reset")  # nothing opens before the with
    if not args.yes and not args.dry_run:
        raise SetupError(f"servo reset erases every setting of servo {args.id}: add --yes")
    with link:
        try:
            reset_option(link, keep_id=args.keep_id, keep_baud=args.keep_baud)
        except SetupError as exc:
            options = link.family.capabilities(link.bus.table).factory_reset_options
            hint = "drop --keep-id and --keep-baud" if "all" in options else "use --keep-id alone"
            raise SetupError(f"{exc} ({hint})") from None
        factory = factory_baud(link.bus.table)
        if link.ping_clean(args.id, args.baud) is None:
            raise BusError(
                args.port,
                [args.id],
                f"no clean answer at {args.baud} baud; `snakebot "
                f"scan --port {args.port} --all-bauds` shows where the servos are",
            )
        was = link.family
        if not args.keep_id and (args.id, args.baud) != (FACTORY_ID, factory):
            taken = False
            for family in reset_families(link, "all"):  # the protocol it may come back in
                link.speak(family)
                other = link.probe(FACTORY_ID, factory, tries=1)
                taken |= bool(other.models or other.corrupt)
            link.speak(was)
            if taken:
                keep = (
                    "reset with --keep-id, or unplug it"
                    if "keep_id" in link.family.capabilities(link.bus.table).factory_reset_options
                    else "unplug it first"
                )
                raise SetupError(
                    f"after a reset without --keep-id the servo answers as ID {FACTORY_ID} at "
                    f"{factory} baud, where another servo already answers: {keep}"
                )
        if args.dry_run:
            return report_dry_run(
                args,
                {
                    "port": args.port,
                    "id": args.id,
                    "baud": args.baud,
                    "then_id": args.id if args.keep_id else FACTORY_ID,
                    "then_baud": args.baud if args.keep_baud else factory,
                },
            )
        new_id, new_baud, family = factory_reset(
            link, args.id, args.baud, keep_id=args.keep_id, keep_baud=args.keep_baud
        )
    if args.json:
        print_json(
            {
                "port": args.port,
                "id": args.id,
                "new_id": new_id,
                "new_baud": new_baud,
                "new_protocol": family.protocol,
            }
        )
        return 0
    now = f" in Protocol {family.protocol:.1f}" if family != was else ""
    print(f"servo {args.id}: factory reset; it now answers as ID {new_id} at {new_baud} baud{now}")
    if family != was:
        print(
            f"snakebot: the reset put its Protocol Type back to the factory {family.protocol:.1f}"
            f": switch it to {was.protocol:.1f} again (Protocol Type, address 13, e.g. with "
            "Dynamixel Wizard 2.0) before `snakebot config assign-id` gives it its ID and rate "
            "back",
            file=sys.stderr,
        )
    elif (new_id, new_baud) != (args.id, args.baud):
        print(
            f"snakebot: `snakebot scan --port {args.port} --baud {new_baud} --protocol "
            f"{family.protocol:g} --ids {new_id}` finds it; `snakebot config assign-id` gives "
            "it its ID and rate back",
            file=sys.stderr,
        )
    return 0


def run_models(args: argparse.Namespace) -> int:
    """List every servo model with data; loading each one names any broken file and key."""
    rows: list[dict[str, Any]] = []
    for entry in model_entries():
        table = table_for_model(entry.name)
        rows.append(
            {
                "model": table.model,
                "model_number": table.model_number,
                "family": table.family,
                "protocols": list(table.protocols),
                "ticks": table.specs.ticks.count,
                "registers": len(table.registers),
                "file": "shipped" if entry.shipped else str(entry.path),
            }
        )
    if args.json:
        print_json({"models": rows, "folders": [str(f) for f in model_dirs()]})
        return 0
    print(f"{'model':<14} {'number':>6}  {'protocols':<10} {'ticks':>5}  file")
    for row in rows:
        protocols = "/".join(f"{p:.1f}" for p in row["protocols"])
        print(
            f"{row['model']:<14} {row['model_number']:>6}  {protocols:<10} {row['ticks']:>5}  "
            f"{row['file']}"
        )
    return 0


def run_info(args: argparse.Namespace) -> int:
    """Print one servo's model, firmware, health and control table with units."""
    with _link(args, "info") as link:
        info = servo_info(link, args.id, args.baud)
    table = info.table
    rows = []
    for register in info.registers():
        raw = info.values[register.key]
        value = display(register, None, raw, table)[0]
        si = f"{register.to_si(raw):.6g} {register.unit}" if register.unit else ""
        rows.append(
            {
                "address": register.address,
                "name": register.name,
                "key": register.key,
                "value": raw,
                "si": si,
                "eeprom": register.eeprom,
                "access": register.access,
                "shown": value,
            }
        )
    get = info.values.get
    summary = {
        "id": info.servo_id,
        "baud": info.baud,
        "model": table.model,
        "model_number": get("model_number"),
        "firmware": get("firmware_version"),
        "hardware_error": list(info.hardware_errors),
        "temperature_c": get("present_temperature"),
        "input_voltage_v": round(
            table["present_input_voltage"].to_si(get("present_input_voltage", 0)), 3
        ),
        "torque_on": bool(get("torque_enable")),
    }
    if args.json:
        print_json({**summary, "registers": rows})
        return 0
    errors = ", ".join(info.hardware_errors) or "none"
    print(
        f"servo {info.servo_id} at {info.baud} baud: {table.model} (model "
        f"{summary['model_number']}), firmware {summary['firmware']}"
    )
    print(
        f"  hardware error: {errors}; temperature {summary['temperature_c']} degC; input "
        f"{summary['input_voltage_v']:.1f} V; torque {'on' if summary['torque_on'] else 'off'}"
    )
    print(f"  {'addr':>4}  {'name':<24} {'value':>10}  {'SI':<18} memory")
    for row in rows:
        memory = "EEPROM" if row["eeprom"] else "RAM"
        access = "" if row["access"] == "RW" else " (read-only)"
        print(
            f"  {row['address']:>4}  {row['name']:<24} {row['shown']:>10}  {row['si']:<18} "
            f"{memory}{access}"
        )
    return 0
