"""Argument types and options shared by several commands."""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

from snakebot.config.ports import check_port
from snakebot.errors import ConfigError


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not (value > 0 and math.isfinite(value)):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def port_arg(text: str) -> str:
    """argparse type: a serial device path, or the emulator's ``dxlemu://NAME`` URL; any other
    URL (``socket://``, ``spy://...?file=``) is a usage error saying why."""
    try:
        return check_port(text, source="--port")
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(exc.reason) from None


def add_robot_option(parser: argparse.ArgumentParser, default: str | None = "snake8") -> None:
    """``--robot NAME|FILE``."""
    parser.add_argument(
        "--robot",
        default=default,
        required=default is None,
        help="robot name from firmware_configs/robots/ or a path to a robot .toml"
        + (f" (default {default})" if default else ""),
    )


def print_json(payload: object) -> None:
    """One JSON object on stdout."""
    json.dump(payload, sys.stdout, indent=None, allow_nan=False, default=str)
    sys.stdout.write("\n")
    sys.stdout.flush()


def write_report(
    directory: Path, summary: dict[str, object], draw: Callable[[Path], Sequence[Path]]
) -> None:
    """Draw a command's plots into ``directory`` and write ``summary.json`` beside them; the
    summary gains the list of plot paths."""
    directory.mkdir(parents=True, exist_ok=True)
    summary["plots"] = [str(path) for path in draw(directory)]
    (directory / "summary.json").write_text(json.dumps(summary, indent=2, default=str))
