from __future__ import annotations

from pathlib import Path

import pytest

from snakebot.config import load_robot, robot_names
from snakebot.errors import ConfigError
from tests.conftest import edit_robot


def test_shipped_robots_load_by_name() -> None:
    assert {"snake8", "snake12"} <= set(robot_names())
    snake8 = load_robot("snake8")
    assert snake8.joint_count == 8
    assert {j.axis for j in snake8.joints} == {"yaw"}
    assert snake8.servo_ids == tuple(range(1, 9))
    snake12 = load_robot("snake12")
    assert [j.axis for j in snake12.joints[:4]] == ["yaw", "pitch", "yaw", "pitch"]
    assert snake12.servo_ids == tuple(range(1, 13))
    assert snake12.servo.name == "XL430-W250"
    xm430 = load_robot("snake8-xm430")  # snake8 on current-sensing, mode-5-capable servos
    assert xm430.servo.name == "XM430-W350" and xm430.servo_ids == snake8.servo_ids
    assert xm430.servo.physics.stall_torque_nm > snake8.servo.physics.stall_torque_nm


def test_robot_loads_by_path(config_dir: Path) -> None:
    robot = load_robot(config_dir / "robots" / "snake12.toml")
    assert robot.name == "snake12"
    assert robot.body_length_m == pytest.approx(13 * robot.link.length_m)


@pytest.mark.parametrize(
    ("old", "new", "key", "expected"),
    [
        ("baud = 1000000", "baud = 1000001", "bus.baud", "expected one of"),
        ("mass_kg = 0.085", 'mass_kg = "heavy"', "link.mass_kg", "expected a number"),
        ("[gains]", "[gains]\nposition_q = 3", "gains.position_q", "unknown key"),
        ("servo_id = 3", "servo_id = 2", "joints[2].servo_id", "already used by joints[1]"),
        ('axis = "pitch"', 'axis = "roll"', "joints[1].axis", "expected one of ['yaw', 'pitch']"),
        ("lower_rad = -1.5", "lower_rad = 0.5", "joint_defaults.lower_rad", "in [-3.14159, 0] rad"),
        ("radius_m = 0.022", "radius_m = 0.05", "link.radius_m", "does not fit"),
        ('ground = "isotropic"', 'ground = "ice"', "twin.ground", "expected one of"),
        ("timestep_s = 0.002", "timestep_s = -1", "twin.timestep_s", "in [0.0001, 0.02] s"),
    ],
)
def test_bad_config_names_file_and_key(
    config_dir: Path, old: str, new: str, key: str, expected: str
) -> None:
    path = edit_robot(config_dir, "snake12", old, new)
    with pytest.raises(ConfigError) as info:
        load_robot(path)
    assert info.value.key == key
    assert str(path) in str(info.value)
    assert expected in str(info.value)


def with_twin_servo(config_dir: Path, lines: str) -> Path:
    """A copy of snake12 with a ``[twin.servo]`` table holding ``lines``."""
    table = f"[twin.servo]\n{lines}\n\n[joint_defaults]"
    return edit_robot(config_dir, "snake12", "[joint_defaults]", table)


@pytest.mark.parametrize(
    ("value", "expected"),
    [("0.5", "in [0, 0.1] s"), ("-0.001", "in [0, 0.1] s"), ('"2 ms"', "expected a number")],
)
def test_bad_actuator_delay_names_file_and_key(config_dir: Path, value: str, expected: str) -> None:
    path = with_twin_servo(config_dir, f"actuator_delay_s = {value}")
    with pytest.raises(ConfigError) as info:
        load_robot(path)
    assert info.value.key == "twin.servo.actuator_delay_s"
    assert str(path) in str(info.value)
    assert expected in str(info.value)


def test_actuator_delay_is_read_and_absent_means_no_delay_model(config_dir: Path) -> None:
    assert load_robot("snake12").servo.physics.actuator_delay_s is None
    path = with_twin_servo(config_dir, "actuator_delay_s = 0.012")
    assert load_robot(path).servo.physics.actuator_delay_s == 0.012


def test_unknown_robot_lists_known_ones() -> None:
    with pytest.raises(ConfigError, match=r"known robots: .*snake12"):
        load_robot("snake99")


def test_invalid_toml_is_reported(config_dir: Path) -> None:
    path = edit_robot(config_dir, "snake8", "[bus]", "[bus")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_robot(path)


def test_missing_servo_file_is_reported(config_dir: Path) -> None:
    path = edit_robot(config_dir, "snake8", 'servo = "XL430-W250"', 'servo = "XL999"')
    with pytest.raises(ConfigError, match=r"servos/xl999\.toml"):
        load_robot(path)
