"""`snakebot run --policy` through the emulated bus (`snakebot emulate --pty --physics`)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import snakebot.rl
from tests.integration.rl.policies import constant_policy
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.slow,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


def test_a_velocity_policy_drives_the_twin_behind_the_bus(tmp_path: Path) -> None:
    folder = constant_policy(
        tmp_path / "v",
        snakebot.rl.VELOCITY_ENV_ID,
        [0, -0.5, 0, 0],
        3 * 8 + 2 + 2,
        encoding="sinusoid",
    )
    log = tmp_path / "run.csv"
    with emulator("--robot", "snake8", "--physics") as emu:
        run = subprocess.run(
            [
                sys.executable,
                "-m",
                "snakebot",
                "run",
                "--backend",
                "dynamixel",
                "--port",
                emu.port,
                "--robot",
                "snake8",
                "--policy",
                str(folder),
                "--command",
                "0.1,0",
                "--duration",
                "4",
                "--log",
                str(log),
                "--json",
            ],
            capture_output=True,
            text=True,
            timeout=180,
        )
        assert run.returncode == 0, run.stderr
        twin = emu.stop()[-1]
    summary = json.loads(run.stdout)
    assert summary["gait"] == "policy:velocity:sinusoid" and summary["backend"] == "dynamixel"
    assert summary["distance_m"] is None  # the bus knows no pose...
    assert twin["distance_m"] > 0.2  # ...but the twin behind it swam
    assert log.read_text().count("\n") > 100  # telemetry through the same runner
