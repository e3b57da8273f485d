"""The node's control cycle on the twin without ROS (no rclpy needed): what the callbacks would
leave in the inbox goes through the safety layer, and a stop ends exactly at the rest pose."""

from __future__ import annotations

import numpy as np

from snakebot.config import load_robot
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.safety import SafetyLayer
from snakebot.drive.controller import DriveController, GaitChoice
from snakebot.drive.setup import live_gait
from snakebot.ros2.commands import CommandDriver, CommandedGait, CommandInbox, JointTargets, Steer
from snakebot.ros2.serve import serve_commands
from snakebot.session import Snake

ROBOT = load_robot("snake12")


def test_commands_are_clipped_and_slew_limited_and_a_stop_ends_at_rest() -> None:
    records: list[CycleRecord] = []
    inbox = CommandInbox()
    live = live_gait(ROBOT, rate_hz=100.0)
    driver = CommandDriver(
        CommandedGait(live),
        DriveController(live, [GaitChoice("sidewinding")]),
        inbox,
        timeout_s=0.0,
    )
    asked = np.full(12, 0.2)
    asked[0] = ROBOT.upper_rad[0] + 1.0  # outside the limits

    def script() -> str | None:
        cycle = len(records)
        if cycle == 1:
            inbox.put(JointTargets(asked))
        elif cycle == 150:
            inbox.put(Steer(0.5, 0.3))
        return "done" if cycle >= 450 else None

    with Snake.prepare(ROBOT, "twin") as snake:
        result = serve_commands(
            snake.backend,
            driver,
            SafetyLayer.for_robot(ROBOT),
            rate_hz=100.0,
            metrics=RunMetrics(ROBOT.joint_count, ROBOT.body_length_m, ROBOT.total_mass_kg),
            observers=[records.append],
            stop_check=script,
        )
    commands = np.array([r.command_rad for r in records])
    targets = np.array([r.target_rad for r in records])
    assert targets[:150, 0].max() > ROBOT.upper_rad[0]  # the gait passed the target on...
    assert commands[:, 0].max() == ROBOT.upper_rad[0]  # ...the safety layer clipped it
    assert np.allclose(commands[149, 1:], 0.2)
    steps = np.abs(np.diff(commands, axis=0)).max(axis=1)
    assert steps.max() <= ROBOT.max_speed_rad_s * 0.01 * (1 + 1e-9)  # never faster than the servo
    driving = commands[200:450]
    assert np.ptp(driving, axis=0).max() > 0.3  # the steered live gait moved from the pose
    assert result.stopped_by == "done" and np.array_equal(commands[-1], np.zeros(12))
    assert result.summary["commands"] == 2 and result.cycles == len(records)
