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
from tests.pty_emulator import emulator, patient

pytestmark = [
    pytest.mark.pty,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]


def read_all(port: str, address: int, size: int, ids: range, signed: bool = False) -> list[int]:
    """One register of every servo with the bare SDK, asking again while a loaded machine keeps
    the emulator from answering in time (``patient``)."""
    handler = dynamixel_sdk.PortHandler(port)
    assert handler.openPort() and handler.setBaudRate(1_000_000)
    packets = dynamixel_sdk.PacketHandler(2.0)
    read = {1: packets.read1ByteTxRx, 4: packets.read4ByteTxRx}[size]
    try:
        values = []
        for servo_id in ids:

            def one(servo_id: int = servo_id) -> tuple[int, int, int]:
                outcome: tuple[int, int, int] = read(handler, servo_id, address)
                return outcome

            value, result, _ = patient(one)
            assert result == dynamixel_sdk.COMM_SUCCESS
            if signed and value >= 1 << (8 * size - 1):
                value -= 1 << (8 * size)
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


def start_run(robot: Path, port: str, log: Path) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
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
    )


def wait_for_rows(log: Path, rows: int, run: subprocess.Popen[bytes]) -> None:
    deadline = time.monotonic() + 150  # start-up imports MuJoCo: a minute beside two CPU hogs
    while time.monotonic() < deadline and run.poll() is None:
        if log.exists() and log.read_text().count("\n") > rows:
            return
        time.sleep(0.02)
    if run.poll() is not None:
        _out, err = run.communicate()
        said = [line for line in err.decode().splitlines() if "Return Delay" not in line]
        raise AssertionError(
            f"the run ended (exit {run.returncode}) before it logged {rows} rows: "
            + "\n".join(said)[-3000:]
        )
    raise AssertionError(f"the run did not log {rows} rows in 150 s")


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_repeated_signals_shorten_the_stop_and_still_end_in_the_policy(
    policy: str, signum: int, config_dir: Path, tmp_path: Path
) -> None:
    # ramp_s = 3: the runner's ramp-out and the backend's stop ramp last long enough for the
    # second signal to land in the first and the third in the second, even on a loaded machine.
    robot = edit_robot(config_dir, "snake12", 'stop_policy = "hold"', f'stop_policy = "{policy}"')
    robot.write_text(robot.read_text().replace("ramp_s = 1.0", "ramp_s = 3.0", 1))
    log = tmp_path / "run.csv"
    with emulator("--robot", str(robot)) as emu:
        run = start_run(robot, emu.port, log)
        wait_for_rows(log, 40, run)
        started = time.monotonic()
        for at_s in (0.0, 1.0, 2.0):  # gait -> runner ramp-out -> backend's (hurried) stop ramp
            time.sleep(max(0.0, started + at_s - time.monotonic()))
            if run.poll() is None:
                run.send_signal(signum)
        _out, err = run.communicate(timeout=60)
        stopped_s = time.monotonic() - started
        torque = read_all(emu.port, 64, 1, range(1, 13))
        watchdog = read_all(emu.port, 98, 1, range(1, 13), signed=True)
        goals = read_all(emu.port, 116, 4, range(1, 13))
    assert run.returncode == 130, err.decode()
    assert b"Traceback" not in err
    assert stopped_s < 5.0  # not the 3 s ramp-out plus a 3 s stop ramp
    assert torque == [1 if policy == "hold" else 0] * 12
    assert watchdog == [0] * 12  # disarmed, not tripped (-1)
    if policy == "hold":
        assert max(abs(g - 2048) for g in goals) <= 2  # the hurried ramp still got there
    assert read_log(log).values.shape[0] > 40


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_ctrl_c_while_connecting_leaves_no_traceback_and_the_servos_per_policy(
    policy: str, config_dir: Path, tmp_path: Path
) -> None:
    robot = edit_robot(config_dir, "snake12", 'stop_policy = "hold"', f'stop_policy = "{policy}"')
    log = tmp_path / "run.csv"
    with emulator("--robot", str(robot)) as emu:
        run = start_run(robot, emu.port, log)
        deadline = time.monotonic() + 60
        while not log.exists() and time.monotonic() < deadline:  # the log opens just before
            time.sleep(0.002)  # connect, whose broadcast ping alone takes ~0.8 s
        time.sleep(0.3)
        run.send_signal(signal.SIGINT)
        out, err = run.communicate(timeout=60)
        time.sleep(0.3)  # longer than the Bus Watchdog: a servo left armed would trip
        torque = read_all(emu.port, 64, 1, range(1, 13))
        watchdog = read_all(emu.port, 98, 1, range(1, 13), signed=True)
    assert run.returncode == 130, err.decode()
    assert b"Traceback" not in err
    assert out == b""  # stopped during start-up: no run summary
    if policy == "limp":
        assert torque == [0] * 12
    assert watchdog == [0] * 12  # torque on or off, nobody is left armed to trip


def registers_at_the_end(port: str) -> dict[str, list[int]]:
    ids = range(1, 13)
    return {
        "torque": read_all(port, 64, 1, ids),
        "watchdog": read_all(port, 98, 1, ids, signed=True),
        "goal": read_all(port, 116, 4, ids),
        "min": read_all(port, 52, 4, ids),
        "max": read_all(port, 48, 4, ids),
    }


def assert_ended_per_policy(registers: dict[str, list[int]], policy: str) -> None:
    assert registers["torque"] == [1 if policy == "hold" else 0] * 12
    assert registers["watchdog"] == [0] * 12  # disarmed, not tripped (-1)
    for goal, low, high in zip(registers["goal"], registers["min"], registers["max"], strict=True):
        assert low <= goal <= high


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_three_signals_at_the_issues_intervals_still_end_in_the_policy(
    policy: str, signum: int, config_dir: Path, tmp_path: Path
) -> None:
    # Issue 18.1's repro: ~150 rows in, kill; 0.5 s; kill; 0.1 s; kill. The second lands in
    # the runner's ramp-out, the third in the backend's stop: limp used to end torque-on with
    # the Bus Watchdog tripped.
    robot = edit_robot(config_dir, "snake12", 'stop_policy = "hold"', f'stop_policy = "{policy}"')
    log = tmp_path / "run.csv"
    with emulator("--robot", str(robot)) as emu:
        run = start_run(robot, emu.port, log)
        wait_for_rows(log, 150, run)
        for pause_s in (0.5, 0.1, 0.0):
            if run.poll() is None:
                run.send_signal(signum)
            time.sleep(pause_s)
        _out, err = run.communicate(timeout=60)
        time.sleep(0.3)  # longer than the Bus Watchdog: a servo left armed would trip
        registers = registers_at_the_end(emu.port)
    assert run.returncode == 130, err.decode()
    assert b"Traceback" not in err
    assert_ended_per_policy(registers, policy)


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_a_hang_up_ramps_out_and_ends_in_the_policy_with_a_message(
    policy: str, config_dir: Path, tmp_path: Path
) -> None:
    # A dropped SSH session sends SIGHUP: it used to kill the run mid-gait, torque on.
    robot = edit_robot(config_dir, "snake12", 'stop_policy = "hold"', f'stop_policy = "{policy}"')
    log = tmp_path / "run.csv"
    with emulator("--robot", str(robot)) as emu:
        run = start_run(robot, emu.port, log)
        wait_for_rows(log, 150, run)
        run.send_signal(signal.SIGHUP)
        out, err = run.communicate(timeout=60)
        time.sleep(0.3)
        registers = registers_at_the_end(emu.port)
    assert run.returncode == 130, err.decode()
    assert b"Traceback" not in err
    assert b'"interrupted": true' in out  # the summary says so, as after Ctrl-C
    assert_ended_per_policy(registers, policy)
    if policy == "hold":
        assert max(abs(g - 2048) for g in registers["goal"]) <= 2  # the whole ramp-out ran
    assert np.abs(read_log(log).joints("command_rad")[-1]).max() < 1e-6


def test_three_ctrl_c_stop_a_drive_over_the_bus_and_leave_it_limp(
    config_dir: Path, tmp_path: Path
) -> None:
    robot = edit_robot(config_dir, "snake12", 'stop_policy = "hold"', 'stop_policy = "limp"')
    script = tmp_path / "long.txt"
    script.write_text("0 w\n0 w\n0 w\n0 w\n600 q\n")
    log = tmp_path / "drive.csv"
    with emulator("--robot", str(robot)) as emu:
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
                "--script",
                str(script),
                "--log",
                str(log),
                "--json",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        wait_for_rows(log, 150, drive)
        for pause_s in (0.5, 0.1, 0.0):
            if drive.poll() is None:
                drive.send_signal(signal.SIGINT)
            time.sleep(pause_s)
        _out, err = drive.communicate(timeout=60)
        time.sleep(0.3)
        registers = registers_at_the_end(emu.port)
    assert drive.returncode == 130, err.decode()
    assert b"Traceback" not in err
    assert_ended_per_policy(registers, "limp")
