"""Argument types and options shared by several commands."""

from __future__ import annotations

import argparse
import errno
import json
import math
import os
import sys
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from snakebot.config.input_file import MAX_TEXT_CHARS, text_problem
from snakebot.config.ports import check_port
from snakebot.errors import ConfigError, OutputError, OutputExistsError, UsageError


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not (value > 0 and math.isfinite(value)):
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def finite_float(text: str) -> float:
    """argparse type: a finite number."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def bounded_float(low: float, high: float, unit: str = "") -> Callable[[str], float]:
    """argparse type: a number in [low, high] (``unit`` for the message)."""
    where = f"{low:g} to {high:g}{' ' + unit if unit else ''}"

    def parse(text: str) -> float:
        value = finite_float(text)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected a number from {where}, got {text!r}")
        return value

    parse.__name__ = "number"  # argparse names the type in its own messages
    return parse


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return value


RATE_HZ = bounded_float(0.1, 10_000.0, "Hz")
"""argparse type of ``--rate``: a control rate from 0.1 Hz to 10 kHz."""


def port_arg(text: str) -> str:
    """argparse type: a serial device path, or the emulator's ``dxlemu://NAME`` URL; any other
    URL (``socket://``, ``spy://...?file=``) is a usage error saying why."""
    try:
        return check_port(text, source="--port")
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(exc.reason) from None


def robot_arg(text: str) -> str:
    """argparse type of ``--robot``: a robot name or file path without control or
    bidirectional characters (they would be printed back), at most MAX_TEXT_CHARS long."""
    problem = text_problem(text, max_chars=MAX_TEXT_CHARS)
    if problem is not None:
        raise argparse.ArgumentTypeError(f"a robot name or file: {problem}")
    return text


SIM_ROBOT = "snake8"
"""The robot the twin commands use when ``--robot`` is not given; hardware commands have none."""


def add_robot_option(parser: argparse.ArgumentParser, *, hardware: str = "") -> None:
    """``--robot NAME|FILE``, read back with :func:`robot_name`.

    ``hardware`` says when the command drives real servos ("always", or e.g. "with --backend
    dynamixel"); then there is no default for that case and the help says so.
    """
    if hardware == "always":
        default = "required: no default robot on real servos"
    elif hardware:
        default = f"default {SIM_ROBOT} on the twin; required {hardware}"
    else:
        default = f"default {SIM_ROBOT}"
    parser.add_argument(
        "--robot",
        type=robot_arg,
        help=f"robot name from firmware_configs/robots/ or a path to a robot .toml ({default})",
    )


def robot_name(args: argparse.Namespace, *, hardware: bool, what: str) -> str:
    """``--robot``, or :data:`SIM_ROBOT` on the twin; UsageError (exit 2) when ``what`` drives
    real servos and no robot was named."""
    robot: str | None = args.robot
    if robot is not None:
        return robot
    if not hardware:
        return SIM_ROBOT
    raise UsageError(
        f"{what} drives real servos: name their robot with --robot NAME or --robot FILE. "
        f"There is no default robot on hardware: {SIM_ROBOT}'s servo IDs, joint limits, zero "
        "offsets and gains would move someone else's servos"
    )


def print_json(payload: object) -> None:
    """One JSON object on stdout."""
    json.dump(payload, sys.stdout, indent=None, allow_nan=False, default=str)
    sys.stdout.write("\n")
    sys.stdout.flush()


def check_writable(path: Path, what: str, *, force: bool) -> None:
    """OutputError now if file ``path`` cannot be written (its writer opens it only later).

    The output rule comes first: an existing file at ``path`` is refused (OutputExistsError)
    unless ``force``. The file's folder must exist: a typo in a folder name is refused, not
    made. Leaves everything as it was (absent stays absent).
    """
    refuse_replacing(path, what, force=force)
    try:
        if path.is_dir():
            raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
        missing = _missing_folder(path.parent)
        if missing is not None:
            raise OutputError(
                path,
                f"cannot write the {what}: folder {missing} does not exist "
                "(create it first, or name another)",
            )
        existed = path.exists()
        with path.open("ab"):
            pass
        if not existed:
            path.unlink()
    except OSError as exc:
        raise OutputError(path, f"cannot write the {what}: {os_reason(exc)}") from exc


def _missing_folder(folder: Path) -> Path | None:
    """The outermost folder of ``folder``'s path that does not exist (None: it all exists);
    NotADirectoryError for a file in the way."""
    for above in (folder, *folder.parents):
        if above.exists():
            if not above.is_dir():
                raise NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR), str(above))
            break
    return next((f for f in reversed((folder, *folder.parents)) if not f.exists()), None)


def add_force_option(parser: argparse.ArgumentParser) -> None:
    """``--force``: the one way to let a command replace an output that already exists."""
    parser.add_argument(
        "--force",
        action="store_true",
        help="replace output files or folders that already exist (without it, the command "
        "refuses and writes nothing)",
    )


def refuse_replacing(path: Path, what: str, *, force: bool) -> None:
    """OutputExistsError (exit 1) when file ``path`` exists and ``force`` is False.

    The rule for every output: no command replaces an existing file unless told to. Call it
    before anything is written or any servo moves, so a refused run changes nothing.
    """
    if force or not path.is_file():  # a device (/dev/null) or a pipe holds nothing to lose
        return
    raise OutputExistsError(
        path,
        f"the {what} exists and would be replaced: pass --force to replace it, or name "
        "another file",
    )


def refuse_replacing_in(folder: Path, names: Sequence[str], what: str, *, force: bool) -> None:
    """OutputExistsError when folder ``folder`` already holds any of ``names`` (the files the
    command would write there) and ``force`` is False; the message lists them."""
    if force or not folder.is_dir():
        return
    found = sorted(name for name in names if (folder / name).exists())
    if found:
        raise OutputExistsError(
            folder,
            f"holds the {what} files {', '.join(found)}, which would be replaced: pass --force "
            "to replace them, or name another folder",
        )


def check_folder(path: Path, what: str, *, replaces: Sequence[str], force: bool) -> None:
    """OutputError now if files cannot be written into folder ``path``.

    The output rule first: OutputExistsError when the folder holds any of ``replaces`` (the
    files the command writes there) unless ``force``. A missing folder is fine (the command
    makes it when it writes; it is snakebot's output folder, not a user's file) as long as the
    nearest existing folder above it can be written; nothing is created now.
    """
    refuse_replacing_in(path, replaces, what, force=force)
    try:
        above = next(f for f in (path, *path.parents) if f.exists())
        if not above.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR), str(above))
        if above == path:
            with tempfile.TemporaryFile(dir=path):
                pass
        elif not os.access(above, os.W_OK | os.X_OK):
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(above))
    except OSError as exc:
        raise OutputError(path, f"cannot write the {what}: {os_reason(exc)}") from exc


def make_folder(path: Path, what: str) -> None:
    """Create output folder ``path`` (and the folders above it); OutputError naming it."""
    try:
        _make_folder(path)
    except OSError as exc:
        raise OutputError(path, f"cannot write the {what}: {os_reason(exc)}") from exc


def _make_folder(path: Path) -> None:
    for folder in (path, *path.parents):  # mkdir says "File exists" for a file in the way
        if folder.exists() and not folder.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR), str(folder))
    path.mkdir(parents=True, exist_ok=True)


def write_report(
    directory: Path, summary: dict[str, object], draw: Callable[[Path], Sequence[Path]]
) -> None:
    """Draw a command's plots into ``directory`` and write ``summary.json`` beside them; the
    summary gains the list of plot paths. OutputError naming the folder if it cannot be
    written."""
    try:
        _make_folder(directory)
        summary["plots"] = [str(path) for path in draw(directory)]
        (directory / "summary.json").write_text(json.dumps(summary, indent=2, default=str))
    except OSError as exc:
        raise OutputError(directory, f"cannot write the report: {os_reason(exc)}") from exc


def os_reason(exc: OSError) -> str:
    """What the operating system said, with the file it said it about."""
    reason = exc.strerror or str(exc)
    return f"{reason} ({exc.filename})" if exc.filename else reason


def named_by_path(robot: str | None) -> bool:
    """True when ``--robot`` named a file (``.toml`` or an existing path), not a robot name."""
    return robot is not None and (robot.endswith(".toml") or Path(robot).is_file())


def robot_write_target(args: argparse.Namespace, source: Path, what: str) -> Path | None:
    """The robot file a command may write ``what`` into, or None when it must write nothing.

    ``--out FILE`` (a copy of the robot file with the new values; the original is untouched),
    else the robot file itself when ``--robot`` named it by path. A robot named by name (or the
    default) is never written: it may be a file shipped inside the installed package.
    ``--dry-run`` writes nothing. UsageError if ``--out`` is the shipped file itself.
    """
    from snakebot.config.paths import shipped_configs

    if getattr(args, "dry_run", False):
        return None
    out: Path | None = getattr(args, "out", None)
    target = out if out is not None else (source if named_by_path(args.robot) else None)
    if target is None:
        return None
    shipped = shipped_configs().resolve()
    if target.resolve().is_relative_to(shipped) and "_data" in shipped.parts:
        raise UsageError(
            f"{target} is a robot file installed with snakebot; write {what} elsewhere with "
            "--out FILE (a copy) and use --robot FILE from then on"
        )
    return target


def check_robot_copy(args: argparse.Namespace, source: Path) -> None:
    """Check ``--out FILE`` (a copy of robot file ``source`` with new values) before any work:
    an existing FILE is refused without ``--force``. ``--out`` naming the robot file itself
    writes into it, as ``--robot FILE`` alone does (the name says so)."""
    out: Path | None = getattr(args, "out", None)
    if out is None:
        return
    same = out.exists() and out.resolve() == source.resolve()
    check_writable(out, "robot file", force=same or args.force)


def copy_for_write(source: Path, target: Path) -> None:
    """Start ``target`` as a copy of robot file ``source`` (nothing to do when they are one);
    OutputError naming ``target`` if it cannot be written."""
    if target.resolve() == source.resolve():
        return
    try:
        _make_folder(target.parent)
        target.write_bytes(source.read_bytes())
    except OSError as exc:
        raise OutputError(target, f"cannot write the robot file: {os_reason(exc)}") from exc


def not_written_note(args: argparse.Namespace, what: str) -> str:
    """Why a command left every robot file as it was."""
    if getattr(args, "dry_run", False):
        return f"dry run: {what} not written"
    return (
        f"{what} not written: --robot named a robot, not a file; pass --robot FILE.toml to "
        "update that file, or --out FILE for a copy with the new values"
    )


def add_write_back_options(parser: argparse.ArgumentParser, what: str) -> None:
    """``--out FILE`` and ``--dry-run`` (``--no-write`` kept as its old name) for a command
    that writes its result (``what``) into a robot file."""
    parser.add_argument(
        "--out",
        type=Path,
        metavar="FILE",
        help=f"write a copy of the robot file with the new {what} here (the original stays)",
    )
    parser.add_argument(
        "--dry-run",
        "--no-write",
        dest="dry_run",
        action="store_true",
        help=f"write no {what} anywhere (without it, they go into --robot FILE or --out)",
    )


def gait_arg(text: str) -> str:
    """argparse type: a known gait name (built-in, plugin or registered), else a usage error
    listing the gaits. Nothing is imported: a plugin gait that fails to load, or that two
    plugins offer, is reported when used (exit 1, naming the plugin), not as bad usage."""
    from snakebot.errors import GaitError
    from snakebot.gaits import GAITS

    try:
        GAITS.origin(text)
    except GaitError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def gait_list_arg(text: str) -> str:
    """argparse type: comma-separated known gait names (kept as the text)."""
    for name in (n.strip() for n in text.split(",")):
        if name:
            gait_arg(name)
    return text


def baud_arg(text: str) -> int:
    """argparse type: a baud rate a serial port opens (snakebot.setup.bauds.VENDOR_PORT_BAUDS,
    and the X series' 4.5 Mbps); whether the servo model has it is the model data's to say,
    checked where the command knows the model."""
    from snakebot.setup.bauds import VENDOR_PORT_BAUDS

    try:
        value = int(text)
    except ValueError:
        value = -1
    known = {*(b for opens in VENDOR_PORT_BAUDS.values() for b in opens), 4_500_000}
    if value not in known:
        rates = ", ".join(map(str, sorted(known)))
        raise argparse.ArgumentTypeError(f"expected one of {rates}, got {text!r}")
    return value


def add_bus_options(parser: Any, *, backend: str = "", baud: bool = True) -> None:
    """``--port`` and ``--baud``, the same on every command: no default of their own, the robot
    file's ``bus.port`` / ``bus.baud`` fill them in. ``backend`` names the option that makes them
    apply (``--backend dynamixel``), for the help text."""
    when = f"with {backend}; " if backend else ""
    parser.add_argument(
        "--port",
        type=port_arg,
        help=f"serial port {when}(default: the robot's bus.port)",
    )
    if baud:
        parser.add_argument(
            "--baud",
            type=baud_arg,
            help=f"baud rate {when}(default: the robot's bus.baud)",
        )


def add_dry_run(parser: Any, what: str) -> None:
    """``--dry-run``: check every option and input, say what would happen, write nothing
    (``what``: what the command would otherwise write)."""
    parser.add_argument(
        "--dry-run",
        action="store_true",
        help=f"check everything and show the plan; write nothing ({what})",
    )


def report_dry_run(args: argparse.Namespace, plan: dict[str, object]) -> int:
    """Print what a ``--dry-run`` would have done (``plan``; JSON with ``--json``); exit 0."""
    if getattr(args, "json", False):
        print_json({"dry_run": True, **plan})
    else:
        print("dry run: nothing was written or moved; the plan:")
        for key, value in plan.items():
            print(f"  {key:<14} {value}")
    return 0
