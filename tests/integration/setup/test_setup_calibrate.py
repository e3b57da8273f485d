"""calibrate: offsets from a straight snake, written into the robot file with its comments kept."""

from __future__ import annotations

import math
import stat
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from snakebot.backends.chain.ticks import TickConverter
from snakebot.config import load_robot
from tests.conftest import SHIPPED_ROBOT_FILES, edit_robot
from tests.integration.setup.conftest import Bus, Cli

# Where each servo's shaft sits when its joint is straight (rad from the centre tick).
SHAFTS = [0.05, -0.12, 0.0, 0.2, -0.07, 0.11, -0.2, 0.03, 0.09, -0.15, 0.01, 0.17]


@pytest.fixture
def robot_file(config_dir: Path) -> Path:
    """snake12 with joint 2 mounted reversed (direction = -1)."""
    return edit_robot(config_dir, "snake12", "servo_id = 3\n", "servo_id = 3\ndirection = -1\n")


def lay_straight(bus: Bus) -> None:
    for servo, shaft in zip(bus.chain.servos, SHAFTS, strict=True):
        servo.state = replace(servo.state, position_rad=shaft)


def comments(path: Path) -> list[str]:
    return [line[line.index("#") :] for line in path.read_text().splitlines() if "#" in line]


def test_offsets_are_correct_and_written_back_keeping_comments(
    snake: Bus, cli: Cli, robot_file: Path
) -> None:
    lay_straight(snake)
    before = comments(robot_file)
    code, out, err = cli("calibrate", "--robot", str(robot_file), "--port", snake.url, "--yes")
    assert code == 0, err
    assert "wrote 12 zero offsets" in out
    assert comments(robot_file) == before
    robot = load_robot(robot_file)
    ticks = np.array([s.peek("present_position") for s in snake.chain.servos])
    straight = TickConverter.for_robot(robot).to_rad(ticks)
    assert np.abs(straight).max() < 1e-3  # the straight snake now reads 0 rad everywhere
    assert robot.joints[2].zero_offset_rad == pytest.approx(-0.0, abs=1e-3)
    assert robot.joints[3].zero_offset_rad == pytest.approx(0.2, abs=2e-3)
    # A second calibration replaces the values instead of adding lines.
    snake.servo(4).state = replace(snake.servo(4).state, position_rad=0.1)
    assert cli("calibrate", "--robot", str(robot_file), "--port", snake.url, "--yes")[0] == 0
    text = robot_file.read_text()
    assert text.count("zero_offset_rad") == 13  # [joint_defaults] + one per joint
    assert load_robot(robot_file).joints[3].zero_offset_rad == pytest.approx(0.1, abs=2e-3)


def test_a_reversed_joint_gets_the_sign_of_its_direction(
    snake: Bus, cli: Cli, robot_file: Path
) -> None:
    snake.servo(3).state = replace(snake.servo(3).state, position_rad=0.45)
    code, _, err = cli(
        "calibrate",
        "--robot",
        str(robot_file),
        "--port",
        snake.url,
        "--yes",
        "--max-offset-deg",
        "30",
    )
    assert code == 1  # -1.5 rad would need 112 deg, beyond the +-110 deg Position Limits
    assert "servo 3: Min/Max Position Limit" in err and "widen the Position Limits" in err
    snake.servo(3).state = replace(snake.servo(3).state, position_rad=0.1)
    assert cli("calibrate", "--robot", str(robot_file), "--port", snake.url, "--yes")[0] == 0
    ticks = snake.servo(3).peek("present_position")
    expected = -(ticks - 2048) * 2 * math.pi / 4096
    assert load_robot(robot_file).joints[2].zero_offset_rad == pytest.approx(expected, abs=1e-4)


def test_a_joint_far_from_straight_is_refused(snake: Bus, cli: Cli, robot_file: Path) -> None:
    lay_straight(snake)
    snake.servo(6).state = replace(snake.servo(6).state, position_rad=0.6)
    text = robot_file.read_text()
    code, _, err = cli("calibrate", "--robot", str(robot_file), "--port", snake.url, "--yes")
    assert code == 1
    assert "joint 5 (servo 6) is +34.4 deg" in err and "laid straight" in err
    assert robot_file.read_text() == text


def test_settings_not_applied_yet_are_refused(snake: Bus, cli: Cli, robot_file: Path) -> None:
    snake.servo(2).poke("homing_offset", 100)
    code, _, err = cli("calibrate", "--robot", str(robot_file), "--port", snake.url, "--yes")
    assert code == 1
    assert "servo 2 homing_offset is 100" in err and "snakebot config apply" in err


def test_dry_run_and_no_terminal_write_nothing(snake: Bus, cli: Cli, robot_file: Path) -> None:
    lay_straight(snake)
    text = robot_file.read_text()
    code, out, _ = cli("calibrate", "--robot", str(robot_file), "--port", snake.url, "--dry-run")
    assert code == 0 and "dry run" in out
    code, _, err = cli("calibrate", "--robot", str(robot_file), "--port", snake.url)
    assert code == 1 and "pass --yes" in err
    assert robot_file.read_text() == text


@pytest.mark.parametrize("mode", [0o644, 0o664, 0o640], ids=oct)
def test_the_robot_file_keeps_its_permissions(
    snake: Bus, cli: Cli, robot_file: Path, mode: int
) -> None:
    lay_straight(snake)
    robot_file.chmod(mode)
    code, _, err = cli("calibrate", "--robot", str(robot_file), "--port", snake.url, "--yes")
    assert code == 0, err
    assert stat.S_IMODE(robot_file.stat().st_mode) == mode
    assert load_robot(robot_file).joints[3].zero_offset_rad == pytest.approx(0.2, abs=2e-3)
    assert sorted(p.name for p in robot_file.parent.iterdir()) == SHIPPED_ROBOT_FILES


def test_a_linked_robot_file_stays_a_link(snake: Bus, cli: Cli, robot_file: Path) -> None:
    lay_straight(snake)
    link = robot_file.parent / "mine.toml"
    link.symlink_to(robot_file.name)
    code, _, err = cli("calibrate", "--robot", str(link), "--port", snake.url, "--yes")
    assert code == 0, err
    assert link.is_symlink()
    assert load_robot(robot_file).joints[3].zero_offset_rad == pytest.approx(0.2, abs=2e-3)


def test_a_robot_named_by_name_is_never_written_out_writes_a_copy(
    snake: Bus, cli: Cli, tmp_path: Path
) -> None:
    from snakebot.config.paths import shipped_configs

    shipped = shipped_configs() / "robots" / "snake12.toml"
    original = shipped.read_bytes()
    lay_straight(snake)
    code, out, err = cli("calibrate", "--robot", "snake12", "--port", snake.url, "--yes")
    assert code == 2 and out == ""
    assert "--robot FILE.toml" in err and "--out FILE" in err
    copy = tmp_path / "mine" / "snake12.toml"
    copy.parent.mkdir()  # a file's folder must exist (cli.md: outputs)
    code, out, err = cli(
        "calibrate", "--robot", "snake12", "--port", snake.url, "--yes", "--out", str(copy)
    )
    assert code == 0, err
    assert f"wrote 12 zero offsets into {copy}" in out
    assert shipped.read_bytes() == original
    assert load_robot(copy).joints[1].zero_offset_rad == pytest.approx(SHAFTS[1], abs=2e-3)
