"""servo torque off|on and servo jog, through the real SDK over the emulated chain (dxlemu://)."""

from __future__ import annotations

import json
import math
import threading
import time
from dataclasses import replace
from pathlib import Path

import pytest

from snakebot.emulation.virtual_servo import HardwareError
from tests.conftest import edit_robot
from tests.integration.setup.conftest import Bus, Cli

SNAKE12 = ("--robot", "snake12")
TICKS_PER_DEG = 4096 / 360


def ticks(deg: float, direction: int = 1) -> int:
    return round(2048 + direction * deg * TICKS_PER_DEG)


def test_jog_moves_one_joint_slowly_then_holds_it(snake: Bus, cli: Cli) -> None:
    servo = snake.servo(4)
    start = servo.peek("present_position")
    code, out, err = cli("servo", "jog", *SNAKE12, "--port", snake.url, "4", "15", "--json")
    assert code == 0, err
    result = json.loads(out)
    assert (result["id"], result["joint"], result["target_deg"]) == (4, 3, 15.0)
    assert abs(servo.peek("present_position") - ticks(15)) <= 6
    assert abs(result["end_deg"] - 15.0) < 0.6
    # At 30 deg/s (the default), 15 deg takes half a second of bus time, not a jump.
    assert result["seconds"] >= 0.5 * abs(ticks(15) - start) / (30 * TICKS_PER_DEG)
    assert servo.torque_enabled and servo.peek("goal_position") == ticks(15)
    # The profiles it borrowed are back to the settings' 0 (config diff stays clean).
    assert (servo.peek("profile_velocity"), servo.peek("profile_acceleration")) == (0, 0)
    others = [s for s in snake.chain.servos if s is not servo]
    assert not any(s.torque_enabled for s in others)


def test_jog_speed_sets_how_long_the_move_takes(snake: Bus, cli: Cli) -> None:
    slow = json.loads(
        cli("servo", "jog", *SNAKE12, "--port", snake.url, "2", "20", "--speed", "10", "--json")[1]
    )
    assert slow["seconds"] >= 20 / 10 * 0.9
    code, _, err = cli("servo", "jog", *SNAKE12, "--port", snake.url, "2", "0", "--speed", "2000")
    assert code == 1 and "beyond snake12's joint speed limit" in err


def test_a_reversed_joint_turns_its_shaft_the_other_way(
    snake: Bus, cli: Cli, config_dir: Path
) -> None:
    robot = edit_robot(config_dir, "snake12", "servo_id = 5\n", "servo_id = 5\ndirection = -1\n")
    code, _, err = cli("servo", "jog", "--robot", str(robot), "--port", snake.url, "5", "10")
    assert code == 0, err
    assert abs(snake.servo(5).peek("present_position") - ticks(10, direction=-1)) <= 6
    code, out, err = cli(
        "servo", "jog", "--robot", str(robot), "--port", snake.url, "5", "--", "-0.1rad"
    )
    assert code == 0, err
    assert abs(snake.servo(5).peek("present_position") - ticks(math.degrees(-0.1), -1)) <= 6
    assert out.startswith("servo 5 (joint 4): +10.0 -> -5.") and "holds there" in out


@pytest.mark.parametrize(
    ("angle", "message"),
    [
        ("100", "joint 3 (servo 4): +100.0 deg is outside its limits -85.9..+85.9 deg"),
        ("-1.6rad", "-91.7 deg is outside its limits"),
    ],
)
def test_an_angle_beyond_the_joint_limits_is_refused_and_nothing_moves(
    snake: Bus, cli: Cli, angle: str, message: str
) -> None:
    before = bytes(snake.servo(4).memory.data)
    code, out, err = cli("servo", "jog", *SNAKE12, "--port", snake.url, "4", "--", angle)
    assert (code, out) == (1, "")
    assert message in err and "lower_rad/upper_rad" in err
    assert bytes(snake.servo(4).memory.data)[:64] == before[:64]
    assert not snake.servo(4).torque_enabled


def test_bad_jog_input_names_what_was_expected(snake: Bus, cli: Cli) -> None:
    code, _, err = cli("servo", "jog", *SNAKE12, "--port", snake.url, "4", "15furlongs")
    assert code == 2 and "expected an angle in degrees" in err
    code, _, err = cli("servo", "jog", *SNAKE12, "--port", snake.url, "40", "15")
    assert code == 1 and "no joint has servo_id 40" in err


def test_jog_refuses_a_servo_whose_settings_are_not_applied(snake: Bus, cli: Cli) -> None:
    snake.servo(6).poke("drive_mode", 1)
    code, _, err = cli("servo", "jog", *SNAKE12, "--port", snake.url, "6", "10")
    assert code == 1 and "drive_mode is 1" in err and "snakebot config apply" in err
    assert not snake.servo(6).torque_enabled


def test_jog_dry_run_moves_nothing(snake: Bus, cli: Cli) -> None:
    code, out, err = cli(
        "servo", "jog", *SNAKE12, "--port", snake.url, "4", "15", "--dry-run", "--json"
    )
    assert code == 0, err
    plan = json.loads(out)
    assert plan["dry_run"] is True and plan["target_deg"] == 15.0
    assert not snake.servo(4).torque_enabled
    assert snake.servo(4).peek("goal_position") != ticks(15)


def test_torque_on_holds_where_each_joint_stands(snake: Bus, cli: Cli) -> None:
    for servo_id, rad in ((3, 0.2), (7, -0.4)):
        servo = snake.servo(servo_id)
        servo.state = replace(servo.state, position_rad=rad)
        servo.poke("goal_position", 2048)  # an old goal: enabling torque must not go there
    code, out, err = cli("servo", "torque", "on", *SNAKE12, "--port", snake.url)
    assert code == 0, err
    assert out.count("torque on; holds where it stands") == 12
    for servo in snake.chain.servos:
        assert servo.torque_enabled
        assert servo.peek("goal_position") == servo.peek("present_position")
    assert abs(snake.servo(7).peek("goal_position") - (2048 - 0.4 * 4096 / (2 * math.pi))) <= 1


def test_torque_off_asks_first_then_goes_limp(snake: Bus, cli: Cli) -> None:
    for servo in snake.chain.servos:
        servo.poke("torque_enable", 1)
    code, _, err = cli("servo", "torque", "off", *SNAKE12, "--port", snake.url)
    assert code == 1 and "go limp" in err and "pass --yes" in err
    assert all(s.torque_enabled for s in snake.chain.servos)
    code, out, _ = cli(
        "servo", "torque", "off", *SNAKE12, "--port", snake.url, "--id", "4", "--yes"
    )
    assert (code, out) == (0, "servo 4: torque off; is limp\n")
    assert [s.torque_enabled for s in snake.chain.servos].count(False) == 1
    code, out, _ = cli(
        "servo", "torque", "off", *SNAKE12, "--port", snake.url, "--all", "--yes", "--json"
    )
    assert code == 0 and json.loads(out)["ids"] == list(range(1, 13))
    assert not any(s.torque_enabled for s in snake.chain.servos)


def test_torque_on_is_refused_for_a_latched_error_and_a_servo_outside_its_limits(
    snake: Bus, cli: Cli
) -> None:
    snake.chain.latch_hardware_error(2, HardwareError.OVERLOAD)
    servo = snake.servo(9)
    servo.poke("max_position_limit", 2500)
    servo.state = replace(servo.state, position_rad=1.0)  # tick 2700
    code, _, err = cli("servo", "torque", "on", *SNAKE12, "--port", snake.url)
    assert code == 1
    assert "servo 2 has a latched hardware error (overload)" in err and "servo reboot" in err
    assert "servo 9 stands at tick 2700, outside its Min/Max Position Limit 0..2500" in err
    assert not any(s.torque_enabled for s in snake.chain.servos)


def test_torque_dry_run_and_a_missing_servo(snake: Bus, cli: Cli) -> None:
    snake.servo(4).poke("torque_enable", 1)
    code, out, _ = cli(
        "servo", "torque", "off", *SNAKE12, "--port", snake.url, "--dry-run", "--json"
    )
    assert code == 0 and json.loads(out)["holding_torque"] == [4]
    assert snake.servo(4).torque_enabled
    snake.chain.remove(snake.servo(11))
    code, _, err = cli("servo", "torque", "on", *SNAKE12, "--port", snake.url)
    assert code == 1 and "[servo 11]" in err and "--all-bauds" in err


def test_a_jog_rides_out_replies_lost_while_it_watches_the_move(snake: Bus, cli: Cli) -> None:
    """A loaded pty lost three replies in a row to one of a jog's many position polls; the
    servo moves on by its own profile, so a lost poll is asked again, not fatal."""
    servo, goal = snake.servo(4), ticks(15)

    def lose_replies_once_moving() -> None:
        deadline = time.monotonic() + 30
        while servo.peek("goal_position") != goal and time.monotonic() < deadline:
            time.sleep(0.001)
        snake.chain.drop_replies(4, next_n=3)  # one poll and both its retries

    watcher = threading.Thread(target=lose_replies_once_moving)
    watcher.start()
    try:
        code, _, err = cli(
            "servo", "jog", *SNAKE12, "--port", snake.url, "4", "15", "--speed", "10"
        )  # 1.5 s of bus time: thousands of polls to lose replies in
    finally:
        watcher.join()
    assert code == 0, err
    assert snake.chain.faults_of(servo).drop_next == 0  # the replies were lost during the jog
    assert abs(servo.peek("present_position") - goal) <= 6
