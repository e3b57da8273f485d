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

from snakebot import signals as _signals

_signals.guard_start_up()  # first: a Ctrl-C from here on is a clean exit 130, not a traceback

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
