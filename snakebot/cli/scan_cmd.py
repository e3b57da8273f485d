"""``snakebot scan``: which servos answer on a port, with protocol, model, firmware and baud rate.

The search is ``snakebot.setup.scan``, in each servo family (with ``--robot``, its vendor's;
``--protocol`` names one Dynamixel protocol, ``--family`` any one family);
this module prints what it found and says what went wrong in the words of what was seen: two
servos sharing an ID (contradicting or always-corrupt replies), a line that garbles everything,
line noise (a warning: the servos answer), or servos of two families on one port (a warning:
a bus speaks one protocol).
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import TYPE_CHECKING, Any

from snakebot.cli.common import baud_arg, port_arg, print_json, robot_arg
from snakebot.errors import BusError, SnakebotError, UsageError
from snakebot.families import FAMILIES, ServoFamily, families_of, family_for
from snakebot.setup.bauds import family_bauds

if TYPE_CHECKING:
    from snakebot.setup.scan import ScanEntry, ScanReport

DEFAULT_BAUD = 1_000_000
PROTOCOLS = tuple(sorted({f.protocol for f in families_of("dynamixel")}, reverse=True))
FAMILY_NAMES = tuple(f.name for f in FAMILIES)


def protocol_arg(text: str) -> float:
    """argparse type: a protocol version the families speak ("1", "2.0")."""
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if value not in PROTOCOLS:
        known = " or ".join(f"{p:g}" for p in PROTOCOLS)
        raise argparse.ArgumentTypeError(f"expected protocol {known}, got {text!r}")
    return value


def ids_arg(text: str) -> tuple[int, ...]:
    """argparse type: servo IDs as ``A-B`` (inclusive), ``N`` or ``A,B,C`` within 0..253."""
    ids: list[int] = []
    for part in text.split(","):
        low, _, high = part.strip().partition("-")
        if not low.isdigit() or (high and not high.isdigit()):
            raise argparse.ArgumentTypeError(f"expected IDs like 1-20 or 1,5,7, got {text!r}")
        first, last = int(low), int(high or low)
        if not 0 <= first <= last <= 253:
            raise argparse.ArgumentTypeError(f"expected IDs within 0..253, got {part!r}")
        ids += range(first, last + 1)
    return tuple(sorted(set(ids)))


def add_parser(subparsers: Any) -> None:
    """Register the ``scan`` command."""
    parser = subparsers.add_parser("scan", help="list the servos that answer on a port")
    parser.add_argument(
        "--robot",
        type=robot_arg,
        help="a robot name or file whose bus.port and bus.baud fill in --port and --baud "
        "(optional: scan reads, it moves and writes nothing)",
    )
    parser.add_argument(
        "--port",
        type=port_arg,
        help="serial port, e.g. /dev/ttyUSB0 or COM3 (default: the robot's bus.port)",
    )
    bauds = parser.add_mutually_exclusive_group()
    bauds.add_argument(
        "--baud",
        type=baud_arg,
        help=f"baud rate (default: the robot's bus.baud, else {DEFAULT_BAUD})",
    )
    bauds.add_argument(
        "--all-bauds",
        action="store_true",
        help="try every rate the family's models can be set to (X series: 57600, 1000000, "
        "115200, 2000000, 3000000, 4000000, 9600; AX/MX also 500000, 2500000, 19200; Feetech "
        "1000000, 57600, 76800, 115200, 128000, 250000, 500000, 38400)",
    )
    which = parser.add_mutually_exclusive_group()
    which.add_argument(
        "--protocol",
        type=protocol_arg,
        help="search one Dynamixel protocol only, 1 or 2 (default: every family, the robot's "
        "vendor's only and its own first; Protocol 1.0 and Feetech have no broadcast ping, so "
        "each ID is pinged on its own: about 8.7 s per rate at 1 Mbps for all 254 IDs)",
    )
    which.add_argument(
        "--family",
        choices=FAMILY_NAMES,
        help="search one servo family only, e.g. feetech-sts (Feetech STS/SMS, 1 Mbps from the "
        "factory) or feetech-scs",
    )
    parser.add_argument(
        "--ids",
        type=ids_arg,
        metavar="A-B",
        help="the IDs pinged one by one where there is no broadcast ping, e.g. 1-20 (default "
        "0..253; a 20-ID sweep takes under a second)",
    )
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.set_defaults(handler=run, writes=False)


def model_name(model_number: int) -> str:
    """A model number as its name where snakebot knows the model ("model 1234" if not)."""
    from snakebot.servo_tables import table_for_model

    try:
        return table_for_model(model_number).model
    except SnakebotError:
        return f"model {model_number} (unknown to snakebot)"


Plan = list[tuple[ServoFamily, tuple[int, ...]]]


def _plan(args: argparse.Namespace, first: ServoFamily | None) -> Plan:
    """(family, baud rates) in search order: the robot's vendor's families, its own first; or
    only ``--protocol`` (Dynamixel) or ``--family``; without a robot, every family."""
    families = list(FAMILIES if first is None else families_of(first.vendor))
    if args.protocol is not None:
        families = [f for f in families_of("dynamixel") if f.protocol == args.protocol]
    elif args.family is not None:
        families = [f for f in FAMILIES if f.name == args.family]
    elif first is not None:
        families.sort(key=lambda f: f != first)
    return [(f, family_bauds(f) if args.all_bauds else (args.baud,)) for f in families]


def run(args: argparse.Namespace) -> int:
    """Print the servos found; exit 1 when none answer, IDs collide or the line garbles all."""
    from snakebot.servo_tables import table_for_model
    from snakebot.setup.link import Link
    from snakebot.setup.scan import scan

    expected: tuple[int, ...] | None = None
    first: ServoFamily | None = None
    if args.robot is not None:
        from snakebot.config import load_robot

        robot = load_robot(args.robot)
        args.port = args.port or robot.bus.port
        args.baud = args.baud or robot.bus.baud
        expected = tuple(robot.servo_ids)
        first = family_for(table_for_model(robot.servo.name), robot.bus.protocol)
    if args.port is None:
        raise UsageError(
            "name the serial port with --port (`snakebot ports` lists them), or "
            "--robot NAME to use its bus.port"
        )
    args.baud = args.baud or DEFAULT_BAUD
    plan = _plan(args, first)
    start = time.monotonic()
    with Link(args.port, plan[0][1][0], family=plan[0][0]) as link:
        report = scan(
            link,
            plan,
            ids=args.ids,
            notify=lambda text: print(f"scan: {text}", file=sys.stderr, flush=True),
        )
    elapsed = time.monotonic() - start
    bad_lines = report.bad_lines
    servos = [_as_dict(e, bad_lines) for e in report.entries]
    missing = _missing(report, expected)
    if args.json:
        print_json(
            {
                "port": args.port,
                "servos": servos,
                "missing": missing,
                "protocols": list(report.protocols),
                "families": [f.name for f in report.families],
                "mixed": report.mixed,
                "seconds": round(elapsed, 2),
            }
        )
    else:
        for entry in report.entries:
            print(_line(entry, bad_lines))
        print(f"{len(servos)} servo(s) on {args.port} in {elapsed:.1f} s")
    _warn_noise(report)
    _warn_mixed(report)
    _raise_problems(args, report)
    if missing:
        _warn_missing(args, missing, expected)
    return 0


def _missing(report: ScanReport, expected: tuple[int, ...] | None) -> list[int]:
    """The robot's IDs that did not answer; without a robot, the gaps between the IDs found in
    each protocol (a chain numbered 1..N with holes in it looks incomplete)."""
    found = {e.servo_id for e in report.entries}
    if expected is not None:
        return [i for i in expected if i not in found]
    gaps: set[int] = set()
    for family in {e.family for e in report.entries}:
        ids = {e.servo_id for e in report.entries if e.family == family}
        gaps |= {i for i in range(min(ids), max(ids) + 1) if i not in ids}
    return sorted(gaps - found)


def _warn_missing(
    args: argparse.Namespace, missing: list[int], expected: tuple[int, ...] | None
) -> None:
    ids = ", ".join(map(str, missing))
    if expected is not None:
        what = f"{args.robot} has servo(s) {ids}, which did not answer"
    else:
        what = (
            f"ID(s) {ids} did not answer, between IDs {missing[0] - 1} and "
            f"{missing[-1] + 1} that did,"
        )
    if args.all_bauds:
        advice = "at any rate: check its cable, its power and its connector"
    else:
        advice = (
            f"at {args.baud} baud: a servo not set up yet (or left half-way by an "
            f"interrupted setup) listens at another rate; `snakebot scan --port {args.port} "
            "--all-bauds` finds it, and `snakebot config apply` moves it to the robot's rate"
        )
    print(f"snakebot: warning: {what} {advice}", file=sys.stderr)


def _warn_mixed(report: ScanReport) -> None:
    if not report.mixed:
        return
    groups = []
    for family in report.families:
        ids = sorted({e.servo_id for e in report.entries if e.family == family})
        groups.append(f"{family.label}: ID(s) {', '.join(map(str, ids))}")
    vendors = {f.vendor for f in report.families}
    fix = (
        "give each family its own port (a Feetech and a Dynamixel servo share neither protocol "
        "nor control table)"
        if len(vendors) > 1
        else "give each protocol its own port, or switch the X-series servos' Protocol Type "
        "(address 13, Dynamixel Wizard 2.0) so that every servo speaks the same one (AX and MX "
        "Protocol 1.0 firmware speak 1.0 only)"
    )
    print(
        f"snakebot: warning: servos of two protocols share this port ({'; '.join(groups)}). A "
        f"robot's bus speaks one protocol ([bus] protocol): {fix}",
        file=sys.stderr,
    )


def _as_dict(entry: ScanEntry, bad_lines: list[tuple[str, int]]) -> dict[str, Any]:
    clash = (entry.shared or entry.garbled) and entry.line not in bad_lines
    return {
        "id": entry.servo_id,
        "protocol": entry.family.protocol,
        "family": entry.family.name,
        "model": model_name(entry.model_number) if entry.model_number else "?",
        "model_number": entry.model_number,
        "firmware": entry.firmware,
        "baud": entry.baud,
        "duplicate": entry.verdict.reason if clash else None,
        "verdict": entry.verdict.kind.value,
        "note": None if clash else (entry.verdict.reason or None),
        "in_broadcast": entry.in_broadcast,
        "corrupt_replies": entry.corrupt,
        "replies": entry.replies,
    }


def _line(entry: ScanEntry, bad_lines: list[tuple[str, int]]) -> str:
    text = _as_dict(entry, bad_lines)
    line = (
        f"ID {entry.servo_id:>3}  {text['model']:<12} firmware {entry.firmware:<3} "
        f"{entry.family.label} at {entry.baud} baud"
    )
    if text["duplicate"]:
        label = "DUPLICATE ID" if entry.shared else "DUPLICATE ID?"
        return f"{line}  {label}: {text['duplicate']}"
    notes = [text["note"]] if text["note"] else []
    if not entry.in_broadcast and not text["note"]:
        first = "broadcast ping" if entry.family.broadcast_ping else "ping sweep"
        notes.append(f"missing from the {first}, answered on its own")
    if entry.corrupt and not entry.garbled:
        notes.append(f"{entry.corrupt} of {entry.replies} replies corrupt")
    return f"{line}  ({'; '.join(notes)})" if notes else line


def _warn_noise(report: ScanReport) -> None:
    noisy = report.noisy
    if not noisy:
        return
    corrupt = sum(e.corrupt for e in noisy)
    replies = sum(e.replies for e in noisy)
    ids = ", ".join(str(e.servo_id) for e in noisy)
    print(
        f"snakebot: warning: {corrupt} of {replies} replies from ID(s) {ids} were corrupt, yet "
        "each of these servos also answered cleanly: the line is noisy (a loose connector, a "
        "long cable without termination, power wires beside the data line, or a baud rate too "
        "high for the wiring), not shared IDs",
        file=sys.stderr,
    )


def _raise_problems(args: argparse.Namespace, report: ScanReport) -> None:
    from snakebot.setup.errors import DuplicateIdError

    for line in report.bad_lines:
        ids = [e.servo_id for e in report.entries if e.line == line]
        raise BusError(
            args.port,
            ids,
            f"at {line[1]} baud every reply was corrupt ({len(ids)} IDs answered, none cleanly): "
            "this is the line, not shared IDs. Check the cable and connectors, the RS-485 "
            "termination and the power supply, and that nothing else drives the bus",
        )
    clashes = [(e.servo_id, e.baud, _clash_text(e)) for e in report.problems]
    if clashes:
        raise DuplicateIdError(args.port, clashes)
    if not report.entries:
        rates = "any rate" if args.all_bauds else f"{args.baud} baud"
        which = (
            f"in Protocol {args.protocol:.1f} "
            if args.protocol is not None
            else f"as {args.family} "
            if args.family is not None
            else "in any protocol searched "
        )
        raise BusError(
            args.port,
            [],
            f"no servo answered {which}at {rates}: check power (the LED blinks at power "
            "on), the cable, the port name, or try --all-bauds",
        )


def _clash_text(entry: ScanEntry) -> str:
    if entry.garbled:
        return (
            f"{entry.verdict.reason} while other IDs answer cleanly: two servos sharing the "
            "ID garble each other's replies (if only one servo has it, its cable or "
            "connector is damaged)"
        )
    return entry.verdict.reason
