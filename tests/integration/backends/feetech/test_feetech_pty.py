"""A Feetech snake as a user runs it: `snakebot emulate --robot snake12-sts3215 --pty` in one
process, `snakebot run --robot snake12-sts3215 --port <pty>` in another, through the stock
scservo_sdk port handler on a real pseudo-terminal: no `--backend` (the port and the robot's
servos say Feetech), three gaits, exit 0, every command inside the joint limits, the servos
following, and the stop policy ("hold": torque on, at rest) on every servo afterwards."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from snakebot.backends.feetech.sdk import WaitingScsPortHandler, link
from snakebot.config import load_robot
from snakebot.families import family_named
from snakebot.telemetry import read_log
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


def test_three_gaits_run_over_the_pty_emulator_with_the_port_alone(
    config_dir: Path, tmp_path: Path
) -> None:
    path = config_dir / "robots" / "snake12-sts3215.toml"
    robot = load_robot(path)
    with emulator("--robot", str(path)) as emu:
        assert {s["model"] for s in emu.first["servos"]} == {"STS3215"}
        for gait in ("sidewinding", "rolling", "lateral_undulation"):
            log = tmp_path / f"{gait}.csv"
            argv = ["run", "--robot", str(path), "--port", emu.port, "--gait", gait]
            argv += ["--duration", "1.5", "--rate", "50", "--log", str(log), "--json"]
            run = subprocess.run(
                [sys.executable, "-m", "snakebot", *argv],
                capture_output=True,
                text=True,
                timeout=240,
            )
            assert run.returncode == 0, run.stderr
            assert "Traceback" not in run.stderr
            summary = json.loads(run.stdout)
            assert summary["backend"] == "feetech" and summary["cycles"] > 0
            data = read_log(log)
            n = robot.joint_count
            command = np.column_stack([data.column(f"command_rad_{j}") for j in range(n)])
            position = np.column_stack([data.column(f"position_rad_{j}") for j in range(n)])
            assert np.all(command >= robot.lower_rad - 1e-9)
            assert np.all(command <= robot.upper_rad + 1e-9)
            assert np.max(np.abs(command)) > 0.2, gait  # the gait moved the joints
            assert np.max(np.abs(position)) > 0.1, gait  # and the servos followed
            assert torque_on(emu.port, robot.servo_ids) == [1] * n, gait  # "hold"


def torque_on(port: str, ids: tuple[int, ...]) -> list[int]:
    """Torque Enable (40) of each servo, read through scservo_sdk as a user would check."""
    handler = WaitingScsPortHandler(port)
    bus = link(handler, family_named("feetech-sts"))
    assert bus.open(1_000_000)
    try:
        values = []
        for servo_id in ids:
            for _ in range(5):  # a loaded machine can delay the emulator past the SDK's timeout
                data, result, _ = bus.read(servo_id, 40, 1)
                if result == 0 and len(data) == 1:
                    values.append(data[0])
                    break
            else:
                raise AssertionError(f"servo {servo_id} did not answer")
        return values
    finally:
        bus.close()
