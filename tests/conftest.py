"""Shared fixtures: robot configs written to a temporary folder so tests can break them."""

from __future__ import annotations

import shutil
import signal
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

# MUJOCO_GL is not preset here: importing snakebot's backends picks the offscreen platform the way
# any program using snakebot gets it, before a test module's own `import mujoco` could fix GLFW.
import snakebot.backends  # noqa: F401

if TYPE_CHECKING:
    from snakebot.testing.cluster import LoopbackCluster

REPO = Path(__file__).resolve().parents[1]
CONFIGS = REPO / "firmware_configs"
SHIPPED_ROBOT_FILES = sorted(p.name for p in (CONFIGS / "robots").iterdir())
"""The file names in firmware_configs/robots/: what a copy holds when nothing was left over."""

# A suite started in the background by a non-interactive shell inherits SIGINT ignored, and so would
# every `snakebot` it spawns: the Ctrl-C tests would then send a signal nobody hears. Restore
# Python's handler, so the children start with the default disposition (and KeyboardInterrupt).
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


@pytest.fixture
def config_dir(tmp_path: Path) -> Path:
    """A writable copy of firmware_configs/."""
    target = tmp_path / "firmware_configs"
    shutil.copytree(CONFIGS, target)
    return target


def edit_robot(config_dir: Path, name: str, old: str, new: str) -> Path:
    """Replace text in a copied robot file and return its path."""
    path = config_dir / "robots" / f"{name}.toml"
    text = path.read_text()
    assert old in text, f"{old!r} not in {path}"
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.fixture(scope="session")
def loopback_cluster() -> Iterator[LoopbackCluster]:
    """Two real Ray nodes on 127.0.0.1, one CPU each, shared by the session's cluster tests
    (skipped without the cluster extra). A test that kills a node starts a new one after."""
    pytest.importorskip("ray", reason="the cluster tests need Ray: pip install 'snakebot[cluster]'")
    from snakebot.testing.cluster import LoopbackCluster

    with LoopbackCluster(nodes=2) as cluster:
        yield cluster
