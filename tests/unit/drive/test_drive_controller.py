"""Keys act on the live gait: set points, gaits, pause, stop."""

from __future__ import annotations

import numpy as np
import pytest

from snakebot.config import load_robot
from snakebot.drive.controller import DriveController, GaitChoice
from snakebot.drive.sources import InputEvent
from snakebot.errors import GaitError
from snakebot.gaits.live import LiveGait

ROBOT = load_robot("snake12")


def controller(*gaits: str) -> tuple[DriveController, list[InputEvent]]:
    live = LiveGait(
        12,
        lower_rad=ROBOT.lower_rad,
        upper_rad=ROBOT.upper_rad,
        max_speed_rad_s=ROBOT.max_speed_rad_s,
        period_s=0.01,
    )
    live.start(np.zeros(12))
    seen: list[InputEvent] = []
    drive = DriveController(live, [GaitChoice(g) for g in gaits], on_event=seen.append)
    drive.begin()
    return drive, seen


def press(drive: DriveController, *keys: str) -> None:
    for key in keys:
        drive.apply(key, 1.0)


def test_speed_keys_step_a_quarter_and_go_backwards_below_zero() -> None:
    drive, _ = controller("sidewinding")
    press(drive, "w", "up", "W", "w")
    assert drive.live.setpoint.speed == 1.0
    press(drive, *["s"] * 6)
    assert drive.live.setpoint.speed == -0.5


def test_turn_keys_step_and_x_halts() -> None:
    drive, _ = controller("sidewinding")
    press(drive, "w", "left", "a")
    assert drive.live.setpoint.turn == 0.5
    press(drive, "right", "d", "d")
    assert drive.live.setpoint.turn == -0.25
    press(drive, "x")
    assert (drive.live.setpoint.speed, drive.live.setpoint.turn) == (0.0, 0.0)


def test_set_points_stop_at_the_gait_bounds() -> None:
    drive, _ = controller("sidewinding")
    press(drive, *["a"] * 9, *["+"] * 30)
    status = drive.live.status()
    assert status.setpoint.turn == 1.0
    assert status.bounds is not None
    assert status.setpoint.amplitude == status.bounds.amplitude[1] == 2.0  # 1.2 rad of 0.6


def test_a_stick_sets_speed_as_a_fraction_of_the_speed_limit() -> None:
    drive, _ = controller("sidewinding")
    press(drive, "speed=0.5", "turn=-1")
    status = drive.live.status()
    assert status.setpoint.speed == pytest.approx(0.5 * status.speed_limit)
    assert status.setpoint.turn == -1.0


def test_number_keys_and_tab_switch_gaits_and_a_missing_number_says_so() -> None:
    drive, _ = controller("sidewinding", "rolling")
    press(drive, "2")
    assert drive.live.status().gait == "rolling" and drive.gait_index == 1
    press(drive, "tab")
    assert drive.live.status().gait == "sidewinding"
    press(drive, "7")
    assert drive.notice == "no gait 7: the list has 2"
    assert drive.live.status().gait == "sidewinding"


def test_space_pauses_and_resumes() -> None:
    drive, _ = controller("rolling")
    press(drive, "space")
    assert drive.live.status().mode == "paused"
    press(drive, "space")
    assert drive.live.status().mode == "driving"


@pytest.mark.parametrize("key", ["q", "esc", "ctrl-c", "ctrl-d"])
def test_quit_keys_stop_and_later_keys_do_nothing(key: str) -> None:
    drive, seen = controller("rolling")
    press(drive, "w", key, "w", "2")
    assert drive.stop_reason == "quit" and drive.live.status().mode == "stopping"
    assert [e.key for e in seen] == ["w", key]
    assert drive.live.setpoint.speed == 0.25


def test_keys_without_an_action_are_not_recorded() -> None:
    drive, seen = controller("rolling")
    assert not drive.apply("z", 0.5)
    assert seen == [] and drive.events == 0


def test_a_drive_needs_a_gait() -> None:
    live = LiveGait(2, lower_rad=-1, upper_rad=1, max_speed_rad_s=1, period_s=0.01)
    with pytest.raises(GaitError, match="at least one gait"):
        DriveController(live, [])
