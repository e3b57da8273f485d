"""snakebot: one controller for Dynamixel servo snakes and their MuJoCo twin.

The public API, imported on first use (PEP 562) so that ``import snakebot`` stays light (no
MuJoCo, no dynamixel_sdk)::

    import snakebot
    robot = snakebot.load_robot("snake12")
    with snakebot.connect(robot, backend="twin") as snake:
        summary = snake.run("sidewinding", duration_s=10)

docs/api.md describes every name below.
"""

from __future__ import annotations

import _signal  # type: ignore[import-not-found]  # the builtin behind signal; no stub
import os as _os
import sys as _sys


def _interrupted_at_start_up(signum: int, frame: object) -> None:
    # SIGINT while the snakebot command is still importing, before the CLI's handlers are up:
    # nothing has touched a servo or a file, and a KeyboardInterrupt raised in the middle of an
    # import would print a traceback. Say so and exit 130 at once.
    _os.write(2, b"snakebot: interrupted\n")
    _os._exit(130)


def _started_as_command(argv: list[str], orig_argv: list[str]) -> bool:
    # python -m snakebot (while Python is still finding the module, argv[0] is "-m") or the
    # snakebot console script; not a program of the user's that imports snakebot.
    if argv[:1] == ["-m"]:
        for i, word in enumerate(orig_argv[1:], 1):
            if word == "-m":
                return orig_argv[i + 1 : i + 2] == ["snakebot"]
            if word.startswith("-m"):
                return word[2:] == "snakebot"
        return False
    return bool(argv) and _os.path.basename(argv[0]) in ("snakebot", "snakebot.exe")


# First, with modules Python has loaded already (the builtin _signal, not signal, whose enums
# take milliseconds): from here on a Ctrl-C at start-up is a clean exit 130 (issue 18.8). The
# CLI's entry point replaces the handler with its own.
if _started_as_command(_sys.argv, list(getattr(_sys, "orig_argv", []))) and (
    _signal.getsignal(_signal.SIGINT) is _signal.default_int_handler
):
    _signal.signal(_signal.SIGINT, _interrupted_at_start_up)

import importlib  # noqa: E402
from typing import TYPE_CHECKING, Any  # noqa: E402

__version__ = "0.1.0"

_EXPORTS = {
    "load_robot": "snakebot.session",
    "connect": "snakebot.session",
    "Snake": "snakebot.session",
    "robot_names": "snakebot.session",
    "RunSummary": "snakebot.run_summary",
    "register_gait": "snakebot.gaits.registry",
    "gait_names": "snakebot.gaits.registry",
    "GaitSpec": "snakebot.gaits.registry",
    "ParamSpec": "snakebot.gaits.registry",
    "register_backend": "snakebot.backends.registry",
    "backend_names": "snakebot.backends.registry",
    "BackendSpec": "snakebot.backends.registry",
    "BackendOption": "snakebot.backends.registry",
}

__all__ = [
    "BackendOption",
    "BackendSpec",
    "GaitSpec",
    "ParamSpec",
    "RunSummary",
    "Snake",
    "__version__",
    "backend_names",
    "connect",
    "gait_names",
    "load_robot",
    "register_backend",
    "register_gait",
    "robot_names",
]

if TYPE_CHECKING:
    from snakebot.backends.registry import (
        BackendOption,
        BackendSpec,
        backend_names,
        register_backend,
    )
    from snakebot.gaits.registry import GaitSpec, ParamSpec, gait_names, register_gait
    from snakebot.run_summary import RunSummary
    from snakebot.session import Snake, connect, load_robot, robot_names


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'snakebot' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})
