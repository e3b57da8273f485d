"""Ctrl-C during `snakebot run --backend dynamixel` leaves torque as the robot file says.

Two processes, as a user runs them: `snakebot emulate --pty` and `snakebot run` on its port.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import dynamixel_sdk
import numpy as np
import pytest

from snakebot.telemetry import read_log
from tests.conftest import edit_robot
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


def read_all(port: str, address: int, size: int, ids: range) -> list[int]:
    handler = dynamixel_sdk.PortHandler(port)
    assert handler.openPort() and handler.setBaudRate(1_000_000)
    packets = dynamixel_sdk.PacketHandler(2.0)
    read = {1: packets.read1ByteTxRx, 4: packets.read4ByteTxRx}[size]
    try:
        values = []
        for servo_id in ids:
            value, result, _ = read(handler, servo_id, address)
            assert result == dynamixel_sdk.COMM_SUCCESS
            values.append(value)
        return values
    finally:
        handler.closePort()


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_sigint_ramps_out_and_leaves_torque_as_configured(
    policy: str, config_dir: Path, tmp_path: Path
) -> None:
    robot = edit_robot(config_dir, "snake12", 'stop_policy = "hold"', f'stop_policy = "{policy}"')
    log = tmp_path / "run.csv"
    with emulator("--robot", str(robot)) as emu:
        run = subprocess.Popen(
            [sys.executable, "-m", "snakebot", "run", "--backend", "dynamixel", "--port",
             emu.port, "--robot", str(robot), "--gait", "sidewinding", "--duration", "60",
             "--log", str(log), "--json"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        )
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            if log.exists() and log.read_text().count("\n") > 40:
                break
            time.sleep(0.05)
        run.send_signal(signal.SIGINT)
        out, err = run.communicate(timeout=30)
        assert run.returncode == 130, err.decode()
        assert b'"interrupted": true' in out
        torque = read_all(emu.port, 64, 1, range(1, 13))
        goals = read_all(emu.port, 116, 4, range(1, 13))
    assert torque == [1 if policy == "hold" else 0] * 12
    assert max(abs(g - 2048) for g in goals) <= 2  # ramped to the straight pose first
    data = read_log(log)
    assert data.values.shape[0] > 40
    assert np.abs(data.joints("command_rad")[-1]).max() < 1e-6
