"""`snakebot drive --backend dynamixel` on `snakebot emulate --pty --physics`, as a user runs them.

The scripted tour the twin test drives goes over the emulated bus, and the servos end as the
stop policy says; closing the driver's terminal stops the robot the same way.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from snakebot.backends.chain.bus import ServoBus
from snakebot.config import load_robot
from snakebot.telemetry import read_log
from tests.conftest import edit_robot
from tests.pty_emulator import emulator

if os.name == "posix":
    import pty

pytestmark = [
    pytest.mark.pty,
    pytest.mark.slow,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]

TOUR = Path(__file__).parent / "snake12_tour.txt"
IDS = range(1, 13)


def registers(port: str, key: str) -> list[int]:
    """One register of every servo, read one by one with retries (a loaded machine answers
    late: the emulator runs the twin in real time beside the tests)."""
    with ServoBus(port, 1_000_000, retries=10) as bus:
        return [bus.read(servo_id, key) for servo_id in IDS]


def test_the_scripted_tour_drives_the_twin_through_the_bus_and_ends_holding(
    config_dir: Path, tmp_path: Path
) -> None:
    robot = config_dir / "robots" / "snake12.toml"  # stop_policy = "hold"
    log = tmp_path / "drive.csv"
    with emulator("--robot", str(robot), "--physics") as emu:
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
                str(robot),
                "--gaits",
                "sidewinding,rolling",
                "--script",
                str(TOUR),
                "--log",
                str(log),
                "--json",
            ],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert drive.returncode == 0, drive.stderr
        torque = registers(emu.port, "torque_enable")
        goals = registers(emu.port, "goal_position")
        twin = emu.stop()[-1]
    summary = json.loads(drive.stdout)
    assert summary["stopped_by"] == "quit" and summary["keys"] == 11
    assert torque == [1] * 12  # hold: torque on...
    assert max(abs(g - 2048) for g in goals) <= 2  # ...at the straight pose
    assert twin["distance_m"] > 0.5  # the twin behind the bus sidewound and rolled
    rows = read_log(log)
    commands, times = rows.joints("command_rad"), rows.column("time_s")
    # The slew limit allows the joint speed over the time the last cycle really took (a loaded
    # machine runs late), up to two periods: command k moves at most that far from k - 1.
    allowed = np.clip(np.diff(times)[:-1], 0.01, 0.02) * load_robot("snake12").max_speed_rad_s
    steps = np.abs(np.diff(commands, axis=0)).max(axis=1)
    assert np.all(steps[1:] <= allowed + 1e-5)  # CSV keeps 6 digits
    assert steps.max() <= 0.02 * load_robot("snake12").max_speed_rad_s + 1e-5
    assert np.abs(commands[-1]).max() < 1e-6


def test_closing_the_terminal_stops_the_robot_and_leaves_it_limp(
    config_dir: Path, tmp_path: Path
) -> None:
    robot = edit_robot(config_dir, "snake12", 'stop_policy = "hold"', 'stop_policy = "limp"')
    log = tmp_path / "drive.csv"
    with emulator("--robot", str(robot), "--physics") as emu:
        master, slave = pty.openpty()
        drive = subprocess.Popen(
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
                str(robot),
                "--gaits",
                "sidewinding",
                "--log",
                str(log),
                "--json",
            ],
            stdin=slave,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            start_new_session=True,
        )
        os.close(slave)
        deadline = time.monotonic() + 30
        while not (log.exists() and log.read_text().count("\n") > 50):  # driving
            assert time.monotonic() < deadline and drive.poll() is None, drive.stderr
            time.sleep(0.05)
        os.write(master, b"wwww")
        time.sleep(2.0)
        os.close(master)  # the terminal window closes
        out, err = drive.communicate(timeout=60)
        torque = registers(emu.port, "torque_enable")
        goals = registers(emu.port, "goal_position")
    assert drive.returncode == 1, err.decode()
    assert b"input lost: the terminal closed" in err
    summary = json.loads(out)
    assert summary["stopped_by"].startswith("input lost: the terminal closed")
    assert summary["keys"] == 4
    assert torque == [0] * 12  # limp, as the robot file says
    assert max(abs(g - 2048) for g in goals) <= 2  # after ramping to the straight pose
