"""``snakebot`` command line: ``main(argv) -> int``; exit codes are decided here and only here.

Exit codes: 0 success, 1 a user-fixable error (bad config, unwritable output, bus failure, servo
fault), 2 usage, 3 a bug in snakebot, 130 interrupted.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import traceback
import warnings
from collections.abc import Sequence
from typing import TextIO

from snakebot import __version__
from snakebot.errors import SnakebotError, UsageError

# command name -> module under snakebot.cli providing add_parser(subparsers) and run(args) -> int
COMMANDS = (
    "run", "drive", "model", "gaits", "emulate", "scan", "config", "servo", "calibrate", "tune",
    "sysid",
    "rl",
)

EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_BUG, EXIT_INTERRUPTED = 0, 1, 2, 3, 130


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with one subcommand per module in ``COMMANDS``."""
    parser = argparse.ArgumentParser(
        prog="snakebot", description="Drive a Dynamixel servo snake or its MuJoCo twin."
    )
    parser.add_argument("--version", action="version", version=f"snakebot {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks for errors")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMANDS:
        module = importlib.import_module(f"snakebot.cli.{name}_cmd")
        module.add_parser(subparsers)
    return parser


def _show_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: TextIO | None = None,
    line: str | None = None,
) -> None:
    # Warnings here are advice for the user (a slow bus setting, say), not for a developer.
    print(f"snakebot: warning: {message}", file=file or sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Parse ``argv`` (default ``sys.argv[1:]``), run the command, return its exit code.

    Ctrl-C at any point, building the parser (which imports every command) included, ends with
    ``snakebot: interrupted`` and 130, never a traceback.
    """
    try:
        return _main(argv)
    except KeyboardInterrupt:
        print("snakebot: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


def _main(argv: Sequence[str] | None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: --help (0) or a usage error (2)
        return int(exc.code or 0)
    try:
        return int(args.handler(args))
    except UsageError as exc:
        print(f"snakebot {args.command}: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except SnakebotError as exc:
        if args.debug:
            traceback.print_exc()
        print(f"snakebot: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except BrokenPipeError:
        return EXIT_ERROR
    except Exception:
        traceback.print_exc()
        print(
            "snakebot: internal error (a bug in snakebot); please report it with the traceback",
            file=sys.stderr,
        )
        return EXIT_BUG


def entry_point() -> None:
    """The ``snakebot`` console script and ``python -m snakebot``: warnings as plain advice."""
    try:
        # MuJoCo picks its OpenGL platform when first imported, which building the parser does:
        # on Linux without a display only EGL renders --video offscreen (twin/video.py).
        if sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
            os.environ.setdefault("MUJOCO_GL", "egl")
        warnings.showwarning = _show_warning
        code = main()
    except KeyboardInterrupt:
        print("snakebot: interrupted", file=sys.stderr)
        code = EXIT_INTERRUPTED
    sys.exit(code)
