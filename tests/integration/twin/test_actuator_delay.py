"""The twin's actuator delay: a servo acts on the command of ``actuator_delay_s`` ago."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend, build_model
from snakebot.config import RobotConfig, load_robot
from snakebot.types import JointCommand
from tests.integration.twin.robots import with_delay

_STATE = mujoco.mjtState.mjSTATE_INTEGRATION


def step_response_time(robot: RobotConfig, level_rad: float = 0.05) -> float:
    """Seconds from a 0.3 rad step of joint 0's goal until the joint has moved ``level_rad``."""
    with TwinBackend(robot) as twin:
        timestep = float(twin.model.opt.timestep)
        twin.advance(0.2)  # settle on the floor
        goal = twin.read_state().position_rad
        start = float(goal[0])
        goal[0] += 0.3
        twin.send_command(JointCommand(goal))
        times, moved = [0.0], [0.0]
        while moved[-1] < level_rad:
            twin.advance(timestep)
            times.append(times[-1] + timestep)
            moved.append(float(twin.read_state().position_rad[0]) - start)
    return float(np.interp(level_rad, moved[-2:], times[-2:]))


@pytest.mark.parametrize("delay_s", [0.005, 0.015, 0.1])
def test_a_delayed_servo_answers_a_step_that_much_later(delay_s: float) -> None:
    robot = load_robot("snake12")
    lag = step_response_time(with_delay(robot, delay_s)) - step_response_time(robot)
    # Linear interpolation of the command history makes the lag the delay itself, not the next
    # whole timestep (which would be up to 2 ms late); a quarter step tells the two apart.
    assert lag == pytest.approx(delay_s, abs=robot.twin.timestep_s / 4)


def test_no_delay_model_adds_no_state_and_a_zero_delay_changes_nothing() -> None:
    robot = load_robot("snake8")
    plain, _ = build_model(robot)
    zero, _ = build_model(with_delay(robot, 0.0))
    assert plain.nhistory == 0 and zero.nhistory > 0
    assert mujoco.mj_stateSize(zero, _STATE) == mujoco.mj_stateSize(plain, _STATE) + zero.nhistory
    poses = []
    for model in (plain, zero):
        data = mujoco.MjData(model)
        for k in range(200):
            data.ctrl[:] = 0.5 * np.sin(0.05 * k + np.arange(model.nu))
            mujoco.mj_step(model, data, 5)
        poses.append(data.qpos.copy())
    assert np.array_equal(poses[0], poses[1])


def test_every_delay_has_the_same_layout() -> None:
    robot = load_robot("snake8")
    short, _ = build_model(with_delay(robot, 0.0))
    longest, _ = build_model(with_delay(robot, 0.1))
    assert np.array_equal(short.actuator_history, longest.actuator_history)
    assert mujoco.mj_stateSize(short, _STATE) == mujoco.mj_stateSize(longest, _STATE)
    assert short.actuator_delay.max() == 0.0 and longest.actuator_delay.min() == 0.1
