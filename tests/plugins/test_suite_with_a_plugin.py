"""A user who installs a gait plugin can still run snakebot's own tests: the tests that list
gaits, backends and terrains see the plugin's entries beside the built-in ones and pass."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from tests.plugins.install import install_project

REPO = Path(__file__).resolve().parents[2]
# Every test module that enumerates the registries (gait_names(), GAITS, the backends).
LISTING_TESTS = [
    "tests/unit/gaits/test_gait_registry.py",
    "tests/unit/gaits/test_gait_plugins.py",
    "tests/unit/gaits/test_gait_axes.py",
    "tests/unit/cli/test_cli_gaits.py",
    "tests/unit/backends/test_backend_registry.py",
    "tests/unit/backends/test_terrain_registry.py",
    "tests/unit/backends/twin/test_terrain_params.py",
    "tests/unit/test_session.py",
]


def test_the_registry_tests_pass_with_a_third_party_gait_installed(tmp_path: Path) -> None:
    site = tmp_path / "site"
    site.mkdir()
    install_project(site)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), str(REPO)])}
    listed = subprocess.run(
        [sys.executable, "-m", "snakebot", "gaits"],
        env=env,
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert listed.returncode == 0 and "standing_wave" in listed.stdout  # the plugin is live
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *LISTING_TESTS],
        env=env,
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-2000:]
