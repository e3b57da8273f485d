# PYTHON_ARGCOMPLETE_OK  (argcomplete's marker: this program answers completion requests)
"""``snakebot`` command line: ``main(argv) -> int``; exit codes are decided here and only here.

Exit codes: 0 success, 1 a user-fixable error (bad config, unwritable output, bus failure, servo
fault), 2 usage, 3 a bug in snakebot, 130 interrupted.
"""

from __future__ import annotations

import argparse
import difflib
import importlib
import json
import os
import re
import signal
import sys
import traceback
import warnings
from collections.abc import Iterator, Sequence
from typing import Any, NoReturn, TextIO

from snakebot import __version__
from snakebot import _interrupted_at_start_up as interrupted_at_start_up
from snakebot.backends.offscreen_gl import choose_offscreen_gl
from snakebot.errors import ConfigError, SnakebotError, UsageError
from snakebot.signals import STOP_SIGNALS

# command name -> module under snakebot.cli providing add_parser(subparsers) and run(args) -> int
COMMANDS: tuple[str, ...] = (
    "run",
    "drive",
    "model",
    "gaits",
    "emulate",
    "scan",
    "config",
    "servo",
    "calibrate",
    "tune",
    "sysid",
    "log",
    "rl",
)
COMMANDS += ("robots", "ports")  # issue 9: where robots come from, which serial ports exist
COMMANDS += ("ros2",)  # issue 24: serve a snake as a ROS 2 node (the ros2 extra)

EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_BUG, EXIT_INTERRUPTED = 0, 1, 2, 3, 130


class CliParser(argparse.ArgumentParser):
    """The parser class of every snakebot command and subcommand (``add_subparsers`` hands it
    down): no abbreviated long options, and errors raised as :class:`ParseError` so
    :func:`main` prints them with the usage of the subcommand that was being parsed."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs["allow_abbrev"] = False
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        """Raise ParseError (exit 2) instead of printing and exiting."""
        raise ParseError(self, message)

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        """As argparse, recording the innermost (sub)parser that ran as ``cli_parser``."""
        parsed, extras = super().parse_known_args(args, namespace)
        if not hasattr(parsed, "cli_parser"):
            parsed.cli_parser = self  # a subcommand's parser ran first and set itself
        return parsed, extras

    def parse_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> argparse.Namespace:
        """As argparse, but an unknown option is reported by the subcommand that got it, with
        that subcommand's usage and the nearest option it does have."""
        parsed, extras = self.parse_known_args(args, namespace)
        if extras:
            owner: CliParser = getattr(parsed, "cli_parser", self)
            known = [s for a in owner._actions for s in a.option_strings]
            hint = ""
            close = difflib.get_close_matches(extras[0].split("=", 1)[0], known, n=1)
            if close:
                hint = f" (did you mean {close[0]}?)"
            owner.error(f"unrecognized arguments: {' '.join(extras)}{hint}")
        return parsed


class ParseError(Exception):
    """A usage error found by argparse, with the parser whose usage to show."""

    def __init__(self, parser: argparse.ArgumentParser, message: str) -> None:
        super().__init__(message)
        self.parser = parser
        self.message = message


def build_parser() -> CliParser:
    """The top-level parser with one subcommand per module in ``COMMANDS``.

    Every leaf (sub)command also takes ``--debug`` (after the subcommand too) and ``--json``.
    """
    parser = CliParser(
        prog="snakebot", description="Drive a Dynamixel servo snake or its MuJoCo twin."
    )
    parser.add_argument("--version", action="version", version=f"snakebot {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks for errors")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMANDS:
        module = importlib.import_module(f"snakebot.cli.{name}_cmd")
        module.add_parser(subparsers)
    for _path, leaf in leaf_parsers(parser):
        leaf.add_argument(
            "--debug",
            action="store_true",
            default=argparse.SUPPRESS,  # keeps a --debug given before the command
            help="show tracebacks for errors",
        )
    return parser


def leaf_parsers(
    parser: argparse.ArgumentParser, path: tuple[str, ...] = ()
) -> Iterator[tuple[tuple[str, ...], argparse.ArgumentParser]]:
    """Every (sub)command parser that runs a handler, with its command words (``("tune",
    "gains")``); aliases are listed once."""
    groups = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not groups:
        yield path, parser
        return
    seen: set[int] = set()
    for name, child in groups[0].choices.items():
        if id(child) not in seen:
            seen.add(id(child))
            yield from leaf_parsers(child, (*path, name))


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


_decided_exit_code: int | None = None
"""Set once the command is over: a signal from then on ends the process with this code."""


def main(argv: Sequence[str] | None = None) -> int:
    """Parse ``argv`` (default ``sys.argv[1:]``), run the command, return its exit code.

    Ctrl-C at any point, building the parser (which imports every command) included, ends with
    ``snakebot: interrupted`` and 130, never a traceback.
    """
    global _decided_exit_code
    # MuJoCo picks its OpenGL platform when first imported, which building the parser does:
    # without a display only EGL or OSMesa render --video offscreen.
    choose_offscreen_gl()
    try:
        code = _main(argv)
    except KeyboardInterrupt:
        _decided_exit_code = EXIT_INTERRUPTED
        print(_interrupted_message(), file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:
        # Ctrl-C inside foreign code can come out as another exception: MuJoCo's C extensions
        # turn it into an ImportError ("initialization failed"), ctypes (PyOpenGL, which MuJoCo
        # imports for EGL) into ``ctypes.ArgumentError: argument 1: KeyboardInterrupt``.
        if not (_interrupt_seen or _caused_by_interrupt(exc)):
            raise
        _decided_exit_code = EXIT_INTERRUPTED
        print(_interrupted_message(), file=sys.stderr)
        return EXIT_INTERRUPTED
    _decided_exit_code = code
    return code


def _interrupted_message() -> str:
    """``snakebot: interrupted``, naming the signal when it was not Ctrl-C."""
    if _interrupt_signal is None or _interrupt_signal == signal.SIGINT:
        return "snakebot: interrupted"
    name = signal.Signals(_interrupt_signal).name
    if name == "SIGHUP":
        return "snakebot: interrupted (SIGHUP: the terminal or SSH session hung up)"
    return f"snakebot: interrupted ({name})"


def _caused_by_interrupt(exc: BaseException) -> bool:
    seen: BaseException | None = exc
    while seen is not None:
        if isinstance(seen, KeyboardInterrupt):
            return True
        seen = seen.__cause__ or seen.__context__
    return False


def _main(argv: Sequence[str] | None) -> int:
    words = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    if _interrupt_seen:
        # A Ctrl-C during start-up that a C extension's init swallowed (MuJoCo's pybind11
        # modules do): honour it before the command touches anything.
        raise KeyboardInterrupt
    if "_ARGCOMPLETE" in os.environ:
        _complete(parser)
    try:
        args = parser.parse_args(words)
    except SystemExit as exc:  # argparse: --help or --version (0)
        return int(exc.code or 0)
    except ParseError as exc:
        if "--json" not in words:
            exc.parser.print_usage(sys.stderr)
        return _fail(f"{exc.parser.prog}: error: {exc.message}", EXIT_USAGE, "--json" in words)
    as_json = bool(getattr(args, "json", False))
    try:
        return int(args.handler(args))
    except UsageError as exc:
        return _fail(f"snakebot {args.command}: error: {exc}", EXIT_USAGE, as_json)
    except SnakebotError as exc:
        if args.debug:
            traceback.print_exc()
        leaf = getattr(args, "cli_parser", parser)
        exc = as_flag_error(exc, leaf)
        code = EXIT_USAGE if names_an_option(exc) else EXIT_ERROR
        return _fail(f"snakebot: error: {name_flags(str(exc), leaf)}", code, as_json)
    except BrokenPipeError:
        return EXIT_ERROR
    except Exception:
        if _interrupt_seen:
            raise  # what a stop signal broke, not a bug: main() ends it as interrupted
        traceback.print_exc()
        return _fail(
            "snakebot: internal error (a bug in snakebot); please report it with the traceback",
            EXIT_BUG,
            as_json,
        )


def _complete(parser: argparse.ArgumentParser) -> None:
    """Answer a shell's completion request (argcomplete's protocol: the optional
    ``snakebot[completion]`` extra, docs/cli.md); argcomplete prints the candidates and exits.
    Without argcomplete installed, nothing happens."""
    try:
        import argcomplete
    except ImportError:
        return
    argcomplete.autocomplete(parser)


_UNIT_SUFFIXES = ("_rad", "_rad_s", "_s", "_hz", "_m", "_deg")


def option_flag(parser: argparse.ArgumentParser, name: str) -> str | None:
    """The flag of ``parser`` that gives library keyword ``name``, or None.

    The library names the keyword it was given (``budget``, ``hold_rad``, ``terrain``); a flag
    whose destination is that keyword, or that keyword less its unit suffix (``--hold`` for
    ``hold_rad``, ``--rate`` for ``rate_hz``), is the one the user typed.
    """
    candidates = [name] + [name[: -len(s)] for s in _UNIT_SUFFIXES if name.endswith(s)]
    for candidate in candidates:
        for action in parser._actions:
            longs = [s for s in action.option_strings if s.startswith("--")]
            if action.dest == candidate and longs:
                return longs[0]
    return None


def as_flag_error(exc: SnakebotError, parser: argparse.ArgumentParser) -> SnakebotError:
    """``exc`` as the command line should say it: a ConfigError about a library keyword this
    command takes as a flag becomes one about the flag (``budget: ...`` -> ``--budget: ...``)."""
    if isinstance(exc, ConfigError) and not exc.source.startswith("--"):
        flag = option_flag(parser, exc.source)
        if flag is not None:
            return ConfigError(flag, exc.key, exc.reason)
    return exc


_OPTION_MENTION = re.compile(r"\((?:backend )?option ([a-z][a-z0-9_]*)(?=[);])")


def name_flags(text: str, parser: argparse.ArgumentParser) -> str:
    """``text`` with each ``(option NAME`` / ``(backend option NAME`` (closed by ``)`` or
    ``;``) the library wrote as advice replaced by the flag of ``parser`` that sets it
    (``(--allow-extra-servos)``)."""

    def flag_of(match: re.Match[str]) -> str:
        flag = option_flag(parser, match.group(1))
        return f"({flag}" if flag else match.group(0)

    return _OPTION_MENTION.sub(flag_of, text)


def names_an_option(exc: SnakebotError) -> bool:
    """True for an error about a command-line value (exit 2): a ConfigError whose source is an
    option (``--friction``) once :func:`as_flag_error` has named the flag."""
    return isinstance(exc, ConfigError) and exc.source.startswith("--")


def _fail(message: str, code: int, as_json: bool) -> int:
    """Print ``message`` on stderr; with ``--json`` as one ``{"error", "code"}`` object there
    instead, so stdout holds only what the command itself printed (a scan's findings, say)."""
    if as_json:
        print(json.dumps({"error": message, "code": code}, ensure_ascii=False), file=sys.stderr)
    else:
        print(message, file=sys.stderr)
    return code


def entry_point() -> None:
    """The ``snakebot`` console script and ``python -m snakebot``: warnings as plain advice.

    SIGTERM and SIGHUP (a closed terminal, a dropped SSH session) are treated like Ctrl-C: a
    killed or hung-up run still ramps out and applies the stop policy. Once the command is over,
    those signals are ignored: the servos are as the stop policy left them, and an impatient
    user's third Ctrl-C must not turn the command's exit code into a death by signal while the
    interpreter shuts down (which takes a second on a loaded machine, after Python has put the
    default handlers back).
    """
    global _decided_exit_code
    _install_signal_handlers()
    try:
        warnings.showwarning = _show_warning
        code = main()
    except KeyboardInterrupt:
        _decided_exit_code = code = EXIT_INTERRUPTED
        print(_interrupted_message(), file=sys.stderr)
    _ignore_signals_from_now_on()
    forget_unhandled_interrupt()
    sys.exit(code)


_interrupt_seen = False
"""A stop signal arrived while the command was still running (even if it was swallowed)."""
_interrupt_signal: int | None = None
"""The first stop signal that arrived while the command was running."""


def _on_signal(signum: int, frame: object) -> None:
    global _interrupt_seen, _interrupt_signal
    if _decided_exit_code is None:
        _interrupt_seen = True
        if _interrupt_signal is None:
            _interrupt_signal = signum
        raise KeyboardInterrupt
    # The command is over; the exit code it decided stands.


def forget_unhandled_interrupt() -> None:
    """Clear CPython's record of a KeyboardInterrupt that left code run from a string.

    CPython remembers a KeyboardInterrupt escaping any ``exec``/``eval`` of source text (which
    ``dataclasses`` and ``namedtuple`` do for every class they make, so a Ctrl-C during start-up
    often lands there) and, under ``python -m``, ends the process by SIGINT after it exits, even
    when the interrupt was caught and the exit code decided. Running a string clears it.
    """
    exec("")  # an empty string: runs nothing, clears the flag


def _install_signal_handlers() -> None:
    # Each stop signal raises KeyboardInterrupt, but only where its default action is in place
    # (Python's own SIGINT handler, or the start-up one): a background job keeps ignoring
    # SIGINT, and `nohup` keeps ignoring SIGHUP.
    replaceable = (signal.default_int_handler, interrupted_at_start_up, signal.SIG_DFL)
    for signum in STOP_SIGNALS:
        if signal.getsignal(signum) in replaceable:
            signal.signal(signum, _on_signal)


def _ignore_signals_from_now_on() -> None:
    # SIG_IGN, unlike a Python handler, survives the interpreter's shutdown.
    for signum in STOP_SIGNALS:
        if signal.getsignal(signum) is _on_signal:
            signal.signal(signum, signal.SIG_IGN)
