"""`snakebot run` over `snakebot emulate --pty` for the Protocol 1.0 families, as a user runs them.

Two processes and a real pseudo-terminal: the AX-12A snake (one Read per servo a cycle, no Bus
Watchdog), snake12 with its X-series servos switched to Protocol 1.0 (Bulk Read) and the
2XL430 snake (two axes per case, Protocol 2.0), each running the serpenoid gait the issue names.
The run exits 0, every command stays inside the joint limits, and the servos followed.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from snakebot.config import load_robot
from snakebot.telemetry import read_log
from tests.conftest import edit_robot
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


def robot_file(config_dir: Path, case: str) -> tuple[Path, list[str]]:
    if case == "ax12a":
        return config_dir / "robots" / "snake12-ax12a.toml", []
    if case == "2xl430":
        return config_dir / "robots" / "snake8-2xl430.toml", []
    path = edit_robot(config_dir, "snake12", "protocol = 2.0", "protocol = 1.0")
    return path, ["--protocol", "1"]


@pytest.mark.parametrize("case", ["ax12a", "x-p1", "2xl430"])
def test_a_protocol_1_snake_runs_a_gait_over_the_pty_emulator(
    case: str, config_dir: Path, tmp_path: Path
) -> None:
    path, extra = robot_file(config_dir, case)
    robot = load_robot(path)
    log = tmp_path / "run.csv"
    with emulator("--robot", str(path), *extra) as emu:
        assert {s["protocol"] for s in emu.first["servos"]} == {robot.bus.protocol}
        run = subprocess.run(
            [
                sys.executable,
                "-m",
                "snakebot",
                "run",
                "--backend",
                "dynamixel",
                "--robot",
                str(path),
                "--port",
                emu.port,
                "--gait",
                "serpenoid",
                "--duration",
                "2",
                "--rate",
                "50",
                "--log",
                str(log),
                "--json",
            ],
            capture_output=True,
            text=True,
            timeout=180,
        )
    assert run.returncode == 0, run.stderr
    assert "Traceback" not in run.stderr
    summary = json.loads(run.stdout)
    assert summary["cycles"] > 0 and summary["achieved_rate_hz"] > 10
    data = read_log(log)
    n = robot.joint_count
    command = np.column_stack([data.column(f"command_rad_{j}") for j in range(n)])
    position = np.column_stack([data.column(f"position_rad_{j}") for j in range(n)])
    assert np.all(command >= robot.lower_rad - 1e-9) and np.all(command <= robot.upper_rad + 1e-9)
    assert np.max(np.abs(command)) > 0.2  # the gait moved the joints
    assert np.max(np.abs(position)) > 0.1  # and the servos followed
