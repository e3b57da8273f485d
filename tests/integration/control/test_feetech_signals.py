"""Ctrl-C, SIGTERM and a hang-up during `snakebot run` on a Feetech snake end in its stop policy.

Two processes, as a user runs them: `snakebot emulate --robot snake12-sts3215 --pty` and
`snakebot run --robot ... --port PTY` (no backend named: the robot's servos are Feetech's). What
the servos are left with is read back over the pty with Feetech's own scservo_sdk. A Feetech servo
has no bus watchdog, so the stop policy the host sends is all that decides it.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import scservo_sdk as scs

from snakebot.telemetry import read_log
from tests.conftest import edit_robot
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]

ROBOT = "snake12-sts3215"
IDS = range(1, 13)
TORQUE_ENABLE, GOAL_POSITION = 40, 42  # memory-sts.md
CENTRE = 2048


def read_all(port: str, address: int, size: int) -> list[int]:
    """One register of every servo with the bare scservo_sdk, asking again while a loaded
    machine delays the emulator's answer."""
    handler = scs.PortHandler(port)
    assert handler.openPort() and handler.setBaudRate(1_000_000)
    packets = scs.sms_sts(handler)
    read = {1: packets.read1ByteTxRx, 2: packets.read2ByteTxRx}[size]
    values = []
    try:
        for servo_id in IDS:
            deadline = time.monotonic() + 10.0
            while True:
                value, result, _error = read(servo_id, address)
                if result == scs.COMM_SUCCESS or time.monotonic() > deadline:
                    break
            assert result == scs.COMM_SUCCESS, packets.getTxRxResult(result)
            values.append(value)
    finally:
        handler.closePort()
    return values


def wait_for_rows(log: Path, rows: int, run: subprocess.Popen[bytes]) -> None:
    deadline = time.monotonic() + 150  # start-up imports MuJoCo: a minute beside CPU hogs
    while time.monotonic() < deadline and run.poll() is None:
        if log.exists() and log.read_text().count("\n") > rows:
            return
        time.sleep(0.02)
    raise AssertionError(f"the run did not log {rows} rows")


@pytest.mark.parametrize(
    ("signum", "policy"),
    [
        (signal.SIGINT, "hold"),
        (signal.SIGTERM, "limp"),
        (signal.SIGHUP, "hold"),
        (signal.SIGHUP, "limp"),
    ],
)
def test_a_stop_signal_ramps_out_and_leaves_the_feetech_servos_per_policy(
    signum: int, policy: str, config_dir: Path, tmp_path: Path
) -> None:
    robot = edit_robot(config_dir, ROBOT, 'stop_policy = "hold"', f'stop_policy = "{policy}"')
    log = tmp_path / "run.csv"
    with emulator("--robot", str(robot)) as emu:
        run = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "snakebot",
                "run",
                "--robot",
                str(robot),
                "--port",
                emu.port,
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
        )
        wait_for_rows(log, 100, run)
        run.send_signal(signum)
        out, err = run.communicate(timeout=60)
        time.sleep(0.3)
        torque = read_all(emu.port, TORQUE_ENABLE, 1)
        goals = read_all(emu.port, GOAL_POSITION, 2)
    assert run.returncode == 130, err.decode()
    assert b"Traceback" not in err
    assert b'"interrupted": true' in out
    assert torque == [1 if policy == "hold" else 0] * 12
    if policy == "hold":
        # Ramped to the straight pose first (an uncalibrated snake: Homing Offset 0, centre 2048).
        assert max(abs(g - CENTRE) for g in goals) <= 2
    assert np.abs(read_log(log).joints("command_rad")[-1]).max() < 1e-6
