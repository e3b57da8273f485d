"""The optional packages learning needs, each missing one reported with the extra that brings it.

``snakebot[rl]``: gymnasium (the environments, ``run --policy``); ``snakebot[rl-train]``:
stable-baselines3 and a CPU torch as well (``snakebot rl train/eval/compare``).
"""

from __future__ import annotations

import importlib
from types import ModuleType

from snakebot.errors import MissingDependencyError

RL_INSTALL = "pip install 'snakebot[rl]'"
TRAIN_INSTALL = "pip install 'snakebot[rl-train]'"


def require(module: str, what: str) -> ModuleType:
    """Import ``module``; MissingDependencyError naming the extra that installs it otherwise.

    ``what`` says what needs it ("the learning environments", "rl train").
    """
    install = RL_INSTALL if module == "gymnasium" else TRAIN_INSTALL
    extra = "rl" if module == "gymnasium" else "rl-train"
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise MissingDependencyError(
            f"{what} need{'s' if not what.endswith('s') else ''} {module}, which is not "
            f"installed (the '{extra}' extra): {install}"
        ) from exc
