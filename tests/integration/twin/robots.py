"""Robot configs of any size, derived from the shipped ones, for twin tests."""

from __future__ import annotations

import dataclasses

from snakebot.config import RobotConfig, load_robot
from snakebot.config.schema import GainRegisters


def robot_with_joints(joint_count: int, base: str = "snake8", **twin: object) -> RobotConfig:
    """``base`` with ``joint_count`` joints (IDs 1..N, axes repeating) and twin overrides."""
    robot = load_robot(base)
    pattern = [j.axis for j in robot.joints[:2]]
    joints = tuple(
        dataclasses.replace(robot.joints[0], servo_id=i + 1, axis=pattern[i % 2])
        for i in range(joint_count)
    )
    return dataclasses.replace(
        robot,
        joints=joints,
        twin=dataclasses.replace(robot.twin, **twin),  # type: ignore[arg-type]
    )


def with_gains(robot: RobotConfig, p: int, d: int = 0) -> RobotConfig:
    """``robot`` with other Position P/D gain registers (as its [gains] would give them)."""
    return dataclasses.replace(robot, gains=robot.servo.gains_of(GainRegisters(p, 0, d)))


def with_delay(robot: RobotConfig, delay_s: float | None) -> RobotConfig:
    """``robot`` with another actuator delay (None: no delay model)."""
    physics = dataclasses.replace(robot.servo.physics, actuator_delay_s=delay_s)
    return dataclasses.replace(robot, servo=dataclasses.replace(robot.servo, physics=physics))
