"""Unplugging the adapter mid-run (the pty vanishes) is a clear BusError, exit 1, no traceback.

Two processes, as a user runs them: `snakebot emulate --pty` and `snakebot run` on its port; the
emulator is killed (SIGKILL) mid-run, so the pseudo-terminal's far end disappears at once.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from snakebot.telemetry import read_log

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_the_port_vanishing_mid_run_is_a_bus_error_naming_it(
    policy: str, config_dir: Path, tmp_path: Path
) -> None:
    from tests.conftest import edit_robot

    robot = edit_robot(config_dir, "snake12", 'stop_policy = "hold"', f'stop_policy = "{policy}"')
    emulator = subprocess.Popen(
        [sys.executable, "-m", "snakebot", "emulate", "--pty", "--json", "--robot", str(robot)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    log = tmp_path / "run.csv"
    try:
        assert emulator.stdout is not None
        port = json.loads(emulator.stdout.readline())["port"]
        run = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "snakebot",
                "run",
                "--backend",
                "dynamixel",
                "--port",
                port,
                "--robot",
                str(robot),
                "--gait",
                "sidewinding",
                "--duration",
                "60",
                "--log",
                str(log),
                "--json",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and run.poll() is None:
            if log.exists() and log.read_text().count("\n") > 20:
                break
            time.sleep(0.05)
        emulator.send_signal(signal.SIGKILL)  # the adapter is gone, mid-cycle
        out, err = run.communicate(timeout=60)
    finally:
        if emulator.poll() is None:
            emulator.kill()
        emulator.wait(timeout=10)
    assert run.returncode == 1, err
    assert "Traceback" not in err
    assert "snakebot: error:" in err and "the serial port vanished" in err, err
    assert f"{port} [servo" in err
    assert "the stop policy" in err and "could not be sent" in err  # says what the servos do now
    assert out == ""
    assert read_log(log).values.shape[0] >= 20  # the telemetry taken stays on disk
