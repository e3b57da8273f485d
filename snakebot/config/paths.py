"""Where snakebot finds robot, servo and body files, and the twin's scene.

The repository's top-level ``firmware_configs/`` and ``sim/`` ship inside the wheel as
``snakebot/_data/firmware_configs`` and ``snakebot/_data/sim`` (``setup.py`` copies them at build
time); a source checkout or an editable install reads them from the checkout itself. Either way
they are found with ``importlib.resources``, never by writing anything.

Robot names are looked up on a search path, first match wins (``--robot PATH`` bypasses it):

1. every folder in ``$SNAKEBOT_CONFIG_PATH`` (``os.pathsep``-separated);
2. ``./firmware_configs`` in the current directory;
3. the user's config directory: ``$XDG_CONFIG_HOME/snakebot`` (default ``~/.config/snakebot``) on
   Linux and other POSIX systems, ``~/Library/Application Support/snakebot`` on macOS,
   ``%APPDATA%\\snakebot`` on Windows;
4. the robots shipped with snakebot.

Each folder holds ``robots/``, ``servos/`` and ``bodies/`` like ``firmware_configs/``.
"""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

__all__ = [
    "ConfigFolder",
    "config_search_path",
    "scene_path",
    "shipped_configs",
    "user_config_dir",
]


@dataclass(frozen=True)
class ConfigFolder:
    """One folder on the search path and why it is there (``origin``: ``SNAKEBOT_CONFIG_PATH``,
    ``./firmware_configs``, ``user config`` or ``shipped``)."""

    path: Path
    origin: str


def _data_root() -> Path:
    """The folder holding ``firmware_configs/`` and ``sim/``: the wheel's ``snakebot/_data``, or
    the source checkout an editable install points at."""
    package = resources.files("snakebot")
    packaged = package.joinpath("_data")
    if isinstance(packaged, Path) and packaged.is_dir():
        return packaged
    # Editable install or plain checkout: snakebot/ sits beside firmware_configs/ and sim/.
    return Path(str(package)).resolve().parent


def shipped_configs() -> Path:
    """The ``firmware_configs/`` folder shipped with snakebot (may be absent in a broken
    install; lookups then report the robot as not found)."""
    return _data_root() / "firmware_configs"


def scene_path() -> Path:
    """The twin's MJCF scene (floor, light, tracking camera): ``sim/scene.xml`` as shipped."""
    return _data_root() / "sim" / "scene.xml"


def user_config_dir() -> Path:
    """The per-user config folder (not created here); see the module docstring."""
    if sys.platform == "win32":
        base = os.environ.get("APPDATA")
        return Path(base) / "snakebot" if base else Path.home() / "AppData" / "Roaming" / "snakebot"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Application Support" / "snakebot"
    xdg = os.environ.get("XDG_CONFIG_HOME", "")
    # The XDG spec: a relative XDG_CONFIG_HOME is invalid and is ignored.
    base = Path(xdg) if xdg and Path(xdg).is_absolute() else Path.home() / ".config"
    return base / "snakebot"


def config_search_path() -> list[ConfigFolder]:
    """The folders searched for ``robots/<name>.toml`` (and servos, bodies), in order."""
    folders = [
        ConfigFolder(Path(p), "SNAKEBOT_CONFIG_PATH")
        for p in os.environ.get("SNAKEBOT_CONFIG_PATH", "").split(os.pathsep)
        if p
    ]
    folders.append(ConfigFolder(Path.cwd() / "firmware_configs", "./firmware_configs"))
    folders.append(ConfigFolder(user_config_dir(), "user config"))
    folders.append(ConfigFolder(shipped_configs(), "shipped"))
    return folders
