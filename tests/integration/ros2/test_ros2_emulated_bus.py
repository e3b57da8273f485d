"""`snakebot ros2 --backend dynamixel` on `snakebot emulate --pty`, driven over real rclpy.

Joint commands in ros2_control's topic shape and a trajectory reach the servos through the
safety layer: the ones inside the limits arrive, the one outside is clipped to the limit, no
joint ever leaves its limits; Ctrl-C ends the node at the rest pose in the stop policy (hold:
torque on, the goals straight), and a command stream that goes stale ends it in the stop
policy too (limp: torque off).
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="needs the ros2 extra: pip install 'snakebot[ros2]'")

from snakebot.backends.chain.bus import ServoBus
from snakebot.config import load_robot
from tests.conftest import edit_robot
from tests.integration.ros2.rosclient import STARTUP_S, client, ros2_node
from tests.pty_emulator import emulator

pytestmark = [
    pytest.mark.pty,
    pytest.mark.slow,
    pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX"),
]

ROBOT = load_robot("snake12")
NAMES = [f"joint{i}" for i in range(12)]
TOLERANCE_RAD = 0.03


def registers(port: str, key: str) -> list[int]:
    with ServoBus(port, 1_000_000, retries=10) as bus:
        return [bus.read(servo_id, key) for servo_id in ROBOT.servo_ids]


def test_joint_commands_reach_the_bus_within_limits_and_ctrl_c_ends_holding_at_rest(
    config_dir: Path,
) -> None:
    robot = config_dir / "robots" / "snake12.toml"  # stop_policy = "hold"
    upper = float(ROBOT.upper_rad[0])
    wanted = np.full(12, 0.3)
    asked = wanted.copy()
    asked[0] = upper + 1.0  # outside the limits: clipped to the limit
    wanted[0] = upper
    with emulator("--robot", str(robot)) as emu, client() as ros:
        with ros2_node(
            "--robot", str(robot), "--backend", "dynamixel", "--port", emu.port,
            "--command-timeout", "0",
        ) as node:  # fmt: skip
            ros.wait_for(
                lambda: len(ros.joint_states()) > 10 or not node.running(),
                STARTUP_S,
                "joint_states",
            )
            assert node.running(), node.finish()

            def reached(target: np.ndarray, joints: slice = slice(None)) -> bool:
                now = ros.joint_states()[-1][1]
                return bool(np.abs(now[joints] - target[joints]).max() < TOLERANCE_RAD)

            deadline = time.monotonic() + 30.0
            while not reached(wanted):
                assert time.monotonic() < deadline, ros.joint_states()[-1][1]
                ros.command_joints(NAMES, asked)
                time.sleep(0.05)
            # A trajectory on two joints: the others keep their targets.
            ros.send_trajectory(["joint2", "joint4"], [(0.5, [0.0, -0.2]), (1.0, [-0.3, -0.3])])
            after = wanted.copy()
            after[[2, 4]] = -0.3
            ros.wait_for(lambda: reached(after), 30.0, "the trajectory's end")
            node.interrupt()  # Ctrl-C: rest pose, then the stop policy
            summary = node.finish()
        torque = registers(emu.port, "torque_enable")
        goals = registers(emu.port, "goal_position")
    assert node.proc.returncode == 130, node.err
    assert summary["stopped_by"] == "interrupted (SIGINT)" and summary["refused_commands"] == 0
    measured = np.array([p for _, p, _ in ros.joint_states()])
    assert np.all(measured <= ROBOT.upper_rad + TOLERANCE_RAD)  # never beyond the limits
    assert np.all(measured >= ROBOT.lower_rad - TOLERANCE_RAD)
    assert measured[:, 0].max() > upper - TOLERANCE_RAD  # the clipped joint went to its limit
    assert torque == [1] * 12  # hold: torque on...
    assert max(abs(g - 2048) for g in goals) <= 2  # ...at the straight pose
    servo = [
        status
        for array in ros.heard.diagnostics
        for status in array.status
        if status.name == "snakebot: joint0"
    ]
    assert servo and servo[-1].hardware_id == "servo 1" and servo[-1].message == "OK"
    keys = {value.key for value in servo[-1].values}
    assert {"temperature_c", "input_voltage_v", "hardware_errors"} <= keys


def test_a_stale_command_stream_ends_the_node_limp_when_the_robot_says_limp(
    config_dir: Path,
) -> None:
    robot = edit_robot(config_dir, "snake12", 'stop_policy = "hold"', 'stop_policy = "limp"')
    with emulator("--robot", str(robot)) as emu, client() as ros:
        with ros2_node(
            "--robot", str(robot), "--backend", "dynamixel", "--port", emu.port,
            "--command-timeout", "0.5",
        ) as node:  # fmt: skip
            ros.wait_for(
                lambda: len(ros.joint_states()) > 10 or not node.running(),
                STARTUP_S,
                "joint_states",
            )
            for _ in range(20):  # 1 s of targets, then silence
                ros.command_joints(NAMES, np.full(12, 0.2))
                time.sleep(0.05)
            summary = node.finish()
        torque = registers(emu.port, "torque_enable")
    assert node.proc.returncode == 1, node.err
    assert "no command for 0.5 s; the snake was stopped (limp at the rest pose)" in node.err
    assert summary["stopped_by"] == "no command for 0.5 s"
    assert summary["max_abs_command_rad"] > 0.15  # the targets were played first
    assert torque == [0] * 12  # limp: torque off
