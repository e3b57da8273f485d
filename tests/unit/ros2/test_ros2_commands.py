"""The node's commands without ROS: messages to commands, the gait that plays them, the watchdog."""

from __future__ import annotations

import math

import numpy as np
import pytest

from snakebot.config import load_robot
from snakebot.drive.controller import DriveController, GaitChoice
from snakebot.drive.setup import live_gait
from snakebot.ros2.commands import (
    CommandDriver,
    CommandedGait,
    CommandError,
    CommandInbox,
    JointTargets,
    Steer,
    joint_index,
    positions_from,
    steer_from,
    trajectory_from,
)
from snakebot.ros2.options import NodeOptions, joint_names, split_gait_params

ROBOT = load_robot("snake12")
INDEX = joint_index(joint_names(ROBOT))


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def driver(clock: Clock, *, timeout_s: float = 1.0, on_timeout: str = "stop") -> CommandDriver:
    live = live_gait(ROBOT, rate_hz=100.0)
    gait = CommandedGait(live)
    controller = DriveController(live, [GaitChoice("sidewinding")])
    inbox = CommandInbox(clock)
    made = CommandDriver(gait, controller, inbox, timeout_s=timeout_s, on_timeout=on_timeout)  # type: ignore[arg-type]
    live.start(np.zeros(ROBOT.joint_count))
    return made


def test_names_are_the_twin_models_and_an_empty_name_list_means_every_joint() -> None:
    assert joint_names(ROBOT)[:2] == ("joint0", "joint1") and len(INDEX) == 12
    everything = positions_from([], [0.1] * 12, INDEX, "joint_commands")
    assert np.allclose(everything, 0.1)
    some = positions_from(["joint3"], [0.2], INDEX, "joint_commands")
    assert some[3] == 0.2 and np.isnan(np.delete(some, 3)).all()


@pytest.mark.parametrize(
    ("names", "positions", "says"),
    [
        (["joint99"], [0.1], "unknown joint 'joint99'"),
        (["joint0", "joint1"], [0.1], "1 positions for 2 joint names"),
        (["joint0"], [math.nan], "joint 'joint0' position is nan"),
    ],
)
def test_a_bad_joint_command_is_refused_naming_why(
    names: list[str], positions: list[float], says: str
) -> None:
    with pytest.raises(CommandError, match=says):
        positions_from(names, positions, INDEX, "joint_commands")


def test_cmd_vel_is_clipped_to_the_sticks_range_and_must_be_finite() -> None:
    assert steer_from(3.0, -2.0) == Steer(1.0, -1.0)
    with pytest.raises(CommandError, match="finite"):
        steer_from(math.inf, 0.0)


def test_a_trajectory_must_move_forward_in_time() -> None:
    with pytest.raises(CommandError, match="increase"):
        trajectory_from(["joint0"], [(1.0, [0.1]), (1.0, [0.2])], INDEX)
    with pytest.raises(CommandError, match="no points"):
        trajectory_from(["joint0"], [], INDEX)


def test_a_trajectory_plays_from_the_current_target_linearly_and_holds_its_end() -> None:
    gait = CommandedGait(live_gait(ROBOT, rate_hz=100.0))
    gait.follow(JointTargets(np.full(12, 0.1)), now_s=0.0)
    assert np.allclose(gait.command(0.0), 0.1)
    trajectory = trajectory_from(["joint0"], [(1.0, [0.5]), (2.0, [0.3])], INDEX)
    gait.follow(trajectory, now_s=10.0)
    assert gait.command(10.5)[0] == pytest.approx(0.3)  # halfway from 0.1 to 0.5
    assert gait.command(11.5)[0] == pytest.approx(0.4)
    held = gait.command(20.0)
    assert held[0] == pytest.approx(0.3) and np.allclose(held[1:], 0.1)  # others keep theirs


def test_steering_after_joint_commands_starts_the_live_gait_where_the_joints_were() -> None:
    clock = Clock()
    made = driver(clock)
    made.inbox.put(JointTargets(np.full(12, 0.2)))
    made.apply(0.0)
    assert np.allclose(made.gait.command(0.0), 0.2)
    made.inbox.put(Steer(0.5, 0.0))
    made.apply(0.01)
    assert made.gait.mode == "live"
    first = made.gait.command(0.01)
    assert np.abs(first - 0.2).max() < 1e-9  # no jump: the live gait holds the last target
    assert made.gait.live.setpoint.speed > 0  # and the stick's speed is set, as drive's


def test_until_the_first_command_the_start_pose_is_held() -> None:
    made = driver(Clock())
    pose = np.linspace(-0.2, 0.2, 12)
    made.gait.live.start(pose)
    for k in range(100):
        made.apply(k * 0.01)
        assert np.array_equal(made.gait.command(k * 0.01), pose)
    made.inbox.put(Steer(0.0, 0.0))  # a steer, even standing still, blends into the gait
    made.apply(1.0)
    shapes = [made.gait.command(1.0 + k * 0.01) for k in range(1, 150)]
    assert np.abs(shapes[-1] - pose).max() > 0.1
    steps = np.abs(np.diff([pose, *shapes], axis=0)).max()
    assert steps <= ROBOT.max_speed_rad_s * 0.01  # no jump on the way


def test_the_watchdog_is_armed_by_the_first_command_and_stops_after_the_timeout() -> None:
    clock = Clock()
    made = driver(clock, timeout_s=1.0)
    clock.now = 100.0
    made.apply(0.0)
    assert made.stop_reason is None  # no command yet: waiting for a client is no timeout
    made.inbox.put(Steer(0.5, 0.0))
    made.apply(0.0)
    clock.now = 101.0
    made.apply(1.0)
    assert made.stop_reason is None
    clock.now = 101.2
    made.apply(1.2)
    assert made.stop_reason == "no command for 1 s" and made.timeouts == 1
    assert made.gait.live.status().mode == "stopping"


def test_halt_on_timeout_zeroes_speed_and_turn_and_a_new_command_drives_again() -> None:
    clock = Clock()
    made = driver(clock, timeout_s=0.5, on_timeout="halt")
    made.inbox.put(Steer(0.5, 0.3))
    made.apply(0.0)
    clock.now = 1.0
    made.apply(1.0)
    setpoint = made.gait.live.setpoint
    assert made.stop_reason is None and (setpoint.speed, setpoint.turn) == (0.0, 0.0)
    made.inbox.put(Steer(0.5, 0.0))
    made.apply(1.01)
    assert made.gait.live.setpoint.speed > 0


def test_node_options_name_the_bad_field() -> None:
    with pytest.raises(ValueError, match="command_timeout_s"):
        NodeOptions(command_timeout_s=-1.0)
    assert NodeOptions().gait_choices(ROBOT)[0].name == "sidewinding"
    assert split_gait_params(" amplitude_even=0.5, wavelength=2 ") == [
        "amplitude_even=0.5",
        "wavelength=2",
    ]
