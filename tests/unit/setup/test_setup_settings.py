from __future__ import annotations

from pathlib import Path

import pytest

from snakebot.config import load_robot
from snakebot.errors import ConfigError
from snakebot.setup.settings import load_settings
from tests.conftest import edit_robot


def edit_servo(config_dir: Path, old: str, new: str) -> None:
    path = config_dir / "servos" / "xl430-w250.toml"
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))


@pytest.mark.parametrize("name", ["snake8", "snake12"])
def test_shipped_robots_have_valid_settings(name: str) -> None:
    robot = load_robot(name)
    chain = load_settings(robot)
    assert [s.servo_id for s in chain.servos] == list(robot.servo_ids)
    first = {s.key: s.raw for s in chain.servos[0].settings}
    assert first["return_delay_time"] == 0
    assert first["baud_rate"] == 3  # 1 Mbps, from [bus] baud
    assert (first["operating_mode"], first["drive_mode"], first["homing_offset"]) == (3, 0, 0)
    assert (first["min_position_limit"], first["max_position_limit"]) == (796, 3300)  # ±110 deg
    # [gains] holds registers; loaded into SI and turned back into the same registers.
    gains = (first["position_p_gain"], first["position_i_gain"], first["position_d_gain"])
    assert gains == (640, 0, 4000)
    assert chain.notes == ()


def test_robot_and_joint_overrides_take_precedence(config_dir: Path) -> None:
    path = edit_robot(config_dir, "snake12", "[settings]", "[settings]\nshutdown = 53")
    edit_robot(
        config_dir,
        "snake12",
        "servo_id = 2\n",
        "servo_id = 2\nsettings = { shutdown = 21, return_delay_time_us = 40 }\n",
    )
    chain = load_settings(load_robot(path))
    assert chain.for_id(1).get("shutdown").raw == 53
    assert chain.for_id(2).get("shutdown").raw == 21
    assert chain.for_id(2).get("return_delay_time").raw == 20
    assert chain.for_id(2).get("shutdown").source == "snake12.toml joints[1].settings.shutdown"
    assert "Return Delay Time up to 40" in chain.notes[0]


@pytest.mark.parametrize(
    ("line", "key", "message"),
    [
        ("id = 3", "settings.id", r"comes from the robot file \(\[\[joints\]\] servo_id\)"),
        ("baud_rate = 3", "settings.baud_rate", r"\[bus\] baud"),
        ("position_p_gain = 900", "settings.position_p_gain", r"\[gains\] position_p"),
        ("torque_enable = 1", "settings.torque_enable", "switched by the tools"),
        ("goal_position = 2048", "settings.goal_position", "is a command"),
        ("present_position = 1", "settings.present_position", "read-only"),
        ("shutdown_ms = 1", "settings.shutdown_ms", "does not fit"),
        ("shutdwn = 1", "settings.shutdwn", "did you mean shutdown"),
        ("shutdown = 300", "settings.shutdown", r"outside 0\.\.255 \(raw\)"),
        ("max_voltage_limit_v = 20", "settings.max_voltage_limit_v", r"outside 6\.\.14 V"),
        ('shutdown = "52"', "settings.shutdown", "expected a number"),
    ],
)
def test_bad_robot_settings_name_file_and_key(
    config_dir: Path, line: str, key: str, message: str
) -> None:
    path = edit_robot(config_dir, "snake12", "[settings]", f"[settings]\n{line}")
    with pytest.raises(ConfigError, match=message) as info:
        load_settings(load_robot(path))
    assert info.value.key == key
    assert str(path) in str(info.value)


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("drive_mode = 0 ", "drive_mode = 1 ", "reverse bit"),
        ("operating_mode = 3 ", "operating_mode = 4 ", "needs 3"),
        ("max_position_limit_deg = 110", "max_position_limit_deg = 80", "do not cover joint 0"),
    ],
)
def test_settings_that_run_would_refuse_are_rejected(
    config_dir: Path, old: str, new: str, message: str
) -> None:
    edit_servo(config_dir, old, new)
    robot = load_robot(config_dir / "robots" / "snake12.toml")
    with pytest.raises(ConfigError, match=message) as info:
        load_settings(robot)
    assert "snakebot run` on this chain would refuse" in str(info.value)


def test_settings_must_cover_what_run_checks(config_dir: Path) -> None:
    edit_servo(config_dir, "drive_mode = 0 ", "# drive_mode = 0 ")
    with pytest.raises(ConfigError, match="missing drive_mode") as info:
        load_settings(load_robot(config_dir / "robots" / "snake12.toml"))
    assert info.value.source.endswith("xl430-w250.toml")


def test_a_key_set_twice_in_two_units_is_refused(config_dir: Path) -> None:
    path = edit_robot(
        config_dir,
        "snake12",
        "[settings]",
        "[settings]\nreturn_delay_time = 0\nreturn_delay_time_us = 0",
    )
    with pytest.raises(ConfigError, match="set twice"):
        load_settings(load_robot(path))


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("lock = 1", "lock is never written: a locked EEPROM"),
        ("protocol_type = 1", r"protocol_type is not a setting: the robot file's \[bus\] protocol"),
    ],
)
def test_lock_and_protocol_type_are_never_settings(
    config_dir: Path, line: str, message: str
) -> None:
    robot = "snake12-ax12a" if line.startswith("lock") else "snake12"
    path = edit_robot(config_dir, robot, "[settings]", f"[settings]\n{line}")
    with pytest.raises(ConfigError, match=message) as info:
        load_settings(load_robot(path))
    assert str(path) in str(info.value)


def test_without_a_bus_watchdog_config_apply_refuses_what_run_refuses(config_dir: Path) -> None:
    # An AX has no Bus Watchdog: Alarm Shutdown must cut torque on overload and heat (bits 2, 5),
    # or the servo holds its last goal against an obstacle after the host died. `run` refuses
    # that at connect; `config apply` must not write it in the first place.
    path = edit_robot(config_dir, "snake12-ax12a", "[settings]", "[settings]\nshutdown = 4")
    with pytest.raises(ConfigError, match="Alarm Shutdown is 4, needs bits 2 and 5"):
        load_settings(load_robot(path))
    # The same value on an X-series chain is the user's choice: its watchdog protects it.
    x_series = edit_robot(config_dir, "snake12", "[settings]", "[settings]\nshutdown = 4")
    assert load_settings(load_robot(x_series)).servos


def test_a_feetech_unload_condition_is_refused_by_its_own_name(config_dir: Path) -> None:
    # No Feetech servo has a Bus Watchdog either; its register is the Unload Condition, and the
    # message a user reads beside Feetech's manual must say so.
    path = edit_robot(config_dir, "snake12-sts3215", "[settings]", "[settings]\nshutdown = 4")
    with pytest.raises(ConfigError, match="Unload Condition is 4, needs bits 2 and 5") as info:
        load_settings(load_robot(path))
    assert "Alarm Shutdown" not in str(info.value)


def test_without_a_bus_watchdog_alarm_shutdown_must_be_set(config_dir: Path) -> None:
    servo = config_dir / "servos" / "ax-12a.toml"
    text = servo.read_text()
    servo.write_text(
        "\n".join(line for line in text.splitlines() if not line.startswith("shutdown")) + "\n"
    )
    with pytest.raises(ConfigError, match="missing shutdown") as info:
        load_settings(load_robot(config_dir / "robots" / "snake12-ax12a.toml"))
    assert info.value.source.endswith("ax-12a.toml")
