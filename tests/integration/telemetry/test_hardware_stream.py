"""On the servo chain (the pty emulator, through dynamixel-sdk): the scene is the forward
kinematics of the measured joints, and the servos' temperatures and voltages are streamed."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("foxglove")
pytest.importorskip("mcap")
from snakebot.config import load_robot
from snakebot.telemetry.scene import KinematicLinkPoses
from tests.integration.telemetry.test_mcap_record import read_mcap
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


def test_a_drive_over_the_bus_records_fk_of_the_measured_joints_and_servo_health(
    tmp_path: Path,
) -> None:
    script = tmp_path / "tour.txt"
    script.write_text("0.0 w\n0.0 w\n0.0 w\n0.0 w\n2.5 q\n")
    mcap = tmp_path / "bus.mcap"
    with emulator("--robot", "snake8") as emu:
        drive = subprocess.run(
            [
                sys.executable,
                "-m",
                "snakebot",
                "drive",
                "--backend",
                "dynamixel",
                "--port",
                emu.port,
                "--robot",
                "snake8",
                "--script",
                str(script),
                "--mcap",
                str(mcap),
                "--json",
            ],
            capture_output=True,
            text=True,
            timeout=180,
        )
    assert drive.returncode == 0, drive.stderr
    summary = json.loads(drive.stdout)
    topics, _ = read_mcap(mcap)
    joints = topics["/joints"]
    assert len(joints) == summary["control_cycles"]
    assert "com_m" not in joints[0][1]  # nothing measures where a real snake is

    # Every /tf is the FK of the /joints message logged at the same time.
    robot = load_robot("snake8")
    fk = KinematicLinkPoses(robot)
    by_time = {t: m for t, m in joints}
    checked = 0
    for when, message in topics["/tf"]:
        measured = np.array(by_time[when]["position_rad"])
        xpos, _ = fk.poses(measured)
        got = np.array([[t["translation"][a] for a in "xyz"] for t in message["transforms"]])
        assert np.allclose(got, xpos, atol=2e-6)
        checked += 1
    assert checked >= 30
    moving = [np.abs(np.array(m["position_rad"])).max() for _, m in joints]
    assert max(moving) > 0.1  # the servos followed the gait

    health = [m for _, m in topics["/servo_health"]]
    assert health, "no servo health on the bus backend"
    assert health[-1]["servo_ids"] == list(robot.servo_ids)
    assert len(health[-1]["temperature_c"]) == 8 and len(health[-1]["input_voltage_v"]) == 8
    assert all(20 <= t <= 80 for t in health[-1]["temperature_c"])
    assert all(6 <= v <= 16 for v in health[-1]["input_voltage_v"])
    assert topics["/servo_errors"]  # the error list, sent at the start and on change
