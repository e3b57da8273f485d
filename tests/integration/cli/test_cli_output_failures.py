"""An output that fails mid-run (disk full, a file-size limit) ends the run as an error naming the
file, with the rows already written on disk and the servos left as the stop policy says.

Two processes, as a user runs them: `snakebot emulate --pty` and `snakebot run --backend
dynamixel` on its port, the latter under a file-size limit (ulimit -f) its log outgrows.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import dynamixel_sdk
import numpy as np
import pytest

from snakebot.telemetry import read_log
from tests.conftest import SHIPPED_ROBOT_FILES, edit_robot
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals and rlimits need POSIX"),
]

# About 0.7 s of snake12 telemetry at 100 Hz: long enough to be mid-gait, short enough that a
# loaded machine rarely starves the emulator process of the time to answer before it.
LOG_LIMIT_BYTES = 24_000


def file_size_limit(limit: int) -> Callable[[], None]:
    def apply() -> None:
        import resource

        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return apply


def read_all(port: str, address: int, size: int, ids: range) -> list[int]:
    """One register of every servo, through the stock SDK. A read is tried up to five times: the
    emulator is another process, which a loaded machine may not schedule within the SDK's
    34 ms reply timeout."""
    handler = dynamixel_sdk.PortHandler(port)
    assert handler.openPort() and handler.setBaudRate(1_000_000)
    packets = dynamixel_sdk.PacketHandler(2.0)
    read = {1: packets.read1ByteTxRx, 4: packets.read4ByteTxRx}[size]
    try:
        values = []
        for servo_id in ids:
            for _ in range(5):
                value, result, _ = read(handler, servo_id, address)
                if result == dynamixel_sdk.COMM_SUCCESS:
                    break
            assert result == dynamixel_sdk.COMM_SUCCESS, packets.getTxRxResult(result)
            values.append(value)
        return values
    finally:
        handler.closePort()


def snakebot(*argv: str, limit: int | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "snakebot", *argv],
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=None if limit is None else file_size_limit(limit),
        env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"},
    )


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_a_log_outgrowing_the_file_size_limit_stops_the_robot_by_its_stop_policy(
    policy: str, config_dir: Path, tmp_path: Path
) -> None:
    robot = edit_robot(config_dir, "snake12", 'stop_policy = "hold"', f'stop_policy = "{policy}"')
    log = tmp_path / "run.csv"
    with emulator("--robot", str(robot)) as emu:
        run = snakebot(
            "run",
            "--backend",
            "dynamixel",
            "--port",
            emu.port,
            "--robot",
            str(robot),
            "--gait",
            "sidewinding",
            "--duration",
            "60",
            "--log",
            str(log),
            "--json",
            limit=LOG_LIMIT_BYTES,
        )
        torque = read_all(emu.port, 64, 1, range(1, 13))
        goals = read_all(emu.port, 116, 4, range(1, 13))
    assert run.returncode == 1, run.stderr
    assert f"snakebot: error: {log}: cannot write telemetry row" in run.stderr
    assert "File too large" in run.stderr and "Traceback" not in run.stderr
    assert torque == [1 if policy == "hold" else 0] * 12
    assert max(abs(g - 2048) for g in goals) <= 2  # ramped to the straight pose first
    data = read_log(log)  # every row up to the limit is there, only the last one torn
    assert data.values.shape[0] > 50
    np.testing.assert_array_equal(data.column("cycle"), np.arange(data.values.shape[0]))


def test_a_log_outgrowing_the_file_size_limit_on_the_twin(tmp_path: Path) -> None:
    log = tmp_path / "run.csv"
    run = snakebot("run", "--duration", "60", "--log", str(log), limit=LOG_LIMIT_BYTES)
    assert run.returncode == 1, run.stderr
    assert f"snakebot: error: {log}: cannot write telemetry row" in run.stderr
    assert read_log(log).values.shape[0] > 30  # rows of ~0.7 kB with the head IMU's columns


def test_calibrate_that_cannot_write_leaves_the_robot_file_as_it_was(config_dir: Path) -> None:
    robot = config_dir / "robots" / "snake12.toml"
    before = robot.read_bytes()
    with emulator("--robot", str(robot)) as emu:
        run = snakebot(
            "calibrate", "--robot", str(robot), "--port", emu.port, "--yes", limit=len(before) // 2
        )
    assert run.returncode == 1, run.stderr
    assert f"snakebot: error: {robot}: cannot write the offsets (File too large)" in run.stderr
    assert robot.read_bytes() == before
    assert sorted(p.name for p in robot.parent.iterdir()) == SHIPPED_ROBOT_FILES
