"""The hardware suite (tests/hardware) runs, and passes, against `snakebot emulate --pty`.

What a robot owner does with a real port, done here with the emulator's pseudo-terminal as the
port, so the suite is exercised on every CI run and cannot rot: without SNAKEBOT_PORT it skips;
on factory settings it says to run `config apply`; after it, all of it passes.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]

REPO = Path(__file__).resolve().parents[3]


def hardware_suite(port: str | None, robot: str = "snake12") -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("SNAKEBOT_")}
    if port is not None:
        env.update(SNAKEBOT_PORT=port, SNAKEBOT_ROBOT=robot)
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "tests/hardware"],
        cwd=REPO,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_the_hardware_suite_skips_without_a_port() -> None:
    result = hardware_suite(None)
    assert result.returncode == 0, result.stdout
    assert "4 skipped" in result.stdout


@pytest.mark.parametrize("robot", ["snake12", "snake12-sts3215"])
def test_the_hardware_suite_passes_on_an_emulated_bus_after_config_apply(robot: str) -> None:
    """Dynamixel X-series, and a Feetech STS3215 snake (no broadcast ping, no watchdog)."""
    with emulator("--robot", robot) as emu:
        factory = hardware_suite(emu.port, robot)
        applied = subprocess.run(
            [
                sys.executable,
                "-m",
                "snakebot",
                "config",
                "apply",
                "--robot",
                robot,
                "--port",
                emu.port,
                "--yes",
            ],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert applied.returncode == 0, applied.stderr
        result = hardware_suite(emu.port, robot)
    assert factory.returncode == 1  # factory settings: it names the fix
    assert "1 failed, 3 passed" in factory.stdout
    assert "`snakebot config apply` writes them" in factory.stdout
    assert result.returncode == 0, result.stdout
    assert "4 passed" in result.stdout
