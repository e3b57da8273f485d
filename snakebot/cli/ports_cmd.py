"""``snakebot ports``: the serial ports on this machine (pyserial's ``list_ports``)."""

from __future__ import annotations

import argparse
from typing import Any

from snakebot.cli.common import print_json


def add_parser(subparsers: Any) -> None:
    """Register the ``ports`` command."""
    parser = subparsers.add_parser(
        "ports",
        help="list serial ports (USB adapters such as the U2D2 show their USB IDs)",
        description="Lists the serial ports the operating system reports. A U2D2 or other "
        "FTDI adapter shows as USB VID:PID 0403:6014; pass its device to --port.",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.set_defaults(handler=run, writes=False)


def list_ports() -> list[dict[str, Any]]:
    """One dict per port: device, description, hwid, USB vid/pid (ints or None), serial number,
    manufacturer and product."""
    from serial.tools import list_ports as serial_ports

    return [
        {
            "device": p.device,
            "description": p.description,
            "hwid": p.hwid,
            "vid": p.vid,
            "pid": p.pid,
            "serial_number": p.serial_number,
            "manufacturer": p.manufacturer,
            "product": p.product,
        }
        for p in sorted(serial_ports.comports(), key=lambda p: p.device)
    ]


def run(args: argparse.Namespace) -> int:
    """Print the ports; an empty list is not an error (exit 0) but says what to check."""
    ports = list_ports()
    if args.json:
        print_json({"ports": ports})
        return 0
    for port in ports:
        usb = f"  USB {port['vid']:04x}:{port['pid']:04x}" if port["vid"] is not None else ""
        print(f"{port['device']:<20} {port['description']}{usb}")
    if not ports:
        print(
            "no serial ports found: check the USB cable and the adapter's driver "
            "(on Linux, `dmesg` names the ttyUSB/ttyACM device it created)"
        )
    return 0
