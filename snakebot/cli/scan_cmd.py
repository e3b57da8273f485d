"""``snakebot scan``: which servos answer on a port, with model, firmware and baud rate.

Servos that share an ID are reported: their replies collide, which shows up as corrupt packets or
contradicting model numbers (see snakebot/setup/duplicates.py). A colliding ID drops out of the
broadcast ping, so the IDs missing below the highest one found (and ID 1, where new servos
collide) are pinged one by one.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

from snakebot.cli.common import print_json
from snakebot.config.loader import BAUD_RATES
from snakebot.errors import BusError, SnakebotError

# The SDK's PortHandler accepts these (4.5 Mbps needs a custom handler).
SCAN_BAUDS = tuple(b for b in BAUD_RATES if b <= 4_000_000)
FACTORY_ID = 1


def add_parser(subparsers: Any) -> None:
    """Register the ``scan`` command."""
    parser = subparsers.add_parser("scan", help="list the servos that answer on a port")
    parser.add_argument("--port", required=True, help="serial port, e.g. /dev/ttyUSB0 or COM3")
    bauds = parser.add_mutually_exclusive_group()
    bauds.add_argument("--baud", type=int, default=1_000_000, help="baud rate (default 1000000)")
    bauds.add_argument(
        "--all-bauds",
        action="store_true",
        help=f"try every rate: {', '.join(map(str, SCAN_BAUDS))}",
    )
    parser.add_argument("--protocol", type=float, default=2.0, choices=(2.0,), help="protocol")
    parser.add_argument("--json", action="store_true", help="print JSON")
    parser.set_defaults(handler=run)


def model_name(model_number: int) -> str:
    """A model number as its name where snakebot knows the model."""
    from snakebot.servo_tables import table_for_model

    try:
        return table_for_model(model_number).model
    except SnakebotError:
        return f"model {model_number}"


def scan(port: str, bauds: tuple[int, ...], protocol: float = 2.0) -> list[dict[str, Any]]:
    """Broadcast-ping at each rate; one entry per servo that answered, or whose ID collides.

    An entry with ``"duplicate"`` set says why its replies look like several servos.
    """
    from snakebot.setup.duplicates import collision_reason
    from snakebot.setup.link import Link

    found: list[dict[str, Any]] = []
    with Link(port, bauds[0]) as link:
        for baud in bauds:
            pinged = link.at(baud).broadcast_ping()
            # A shared ID garbles its broadcast slot and drops out: check the gaps too.
            gaps = range(1, max(pinged, default=0) + 3)
            for servo_id in sorted({*pinged, *gaps, FACTORY_ID}):
                reason = collision_reason(link, servo_id, baud)
                if servo_id not in pinged and reason is None:
                    continue
                number, firmware = pinged.get(servo_id, (0, 0))
                found.append(
                    {
                        "id": servo_id,
                        "model": model_name(number) if number else "?",
                        "model_number": number,
                        "firmware": firmware,
                        "baud": baud,
                        "duplicate": reason,
                    }
                )
    return found


def run(args: argparse.Namespace) -> int:
    """Print the servos found; exit 1 when none answer or IDs collide."""
    from snakebot.setup.errors import DuplicateIdError

    bauds = SCAN_BAUDS if args.all_bauds else (args.baud,)
    start = time.monotonic()
    servos = scan(args.port, bauds, args.protocol)
    elapsed = time.monotonic() - start
    if args.json:
        print_json({"port": args.port, "servos": servos, "seconds": round(elapsed, 2)})
    else:
        for s in servos:
            clash = f"  DUPLICATE ID: {s['duplicate']}" if s["duplicate"] else ""
            print(
                f"ID {s['id']:>3}  {s['model']:<12} firmware {s['firmware']:<3} at {s['baud']} "
                f"baud{clash}"
            )
        print(f"{len(servos)} servo(s) on {args.port} in {elapsed:.1f} s")
    clashes = [(s["id"], s["baud"], s["duplicate"]) for s in servos if s["duplicate"]]
    if clashes:
        raise DuplicateIdError(args.port, clashes)
    if not servos:
        rates = "any rate" if args.all_bauds else f"{args.baud} baud"
        raise BusError(
            args.port,
            [],
            f"no servo answered at {rates}: check power (the LED blinks at power "
            "on), the cable, the port name, or try --all-bauds",
        )
    return 0
