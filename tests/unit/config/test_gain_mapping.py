"""Each model's position-loop registers in SI: P/I/D Gain (X, MX) or Compliance Slope (AX).

A robot file's ``[gains]`` takes the keys its servo's loop has; the backend, the emulator's twin
and ``config apply`` all go through ``ServoModel.gain_writes`` / ``gains_from``.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from snakebot.config import load_robot
from snakebot.config.loader import load_servo_model
from snakebot.errors import ConfigError
from snakebot.tuning.gain_search import search_gains
from snakebot.tuning.gains import GainTest
from snakebot.types import PDGains
from tests.conftest import CONFIGS, edit_robot

AX_ROBOT = CONFIGS / "robots" / "snake12-ax12a.toml"
AX_RAD_PER_TICK = math.radians(300) / 1024  # e-Manual ax-12a.md: 0.29 deg a tick
SLOPES = {"cw_compliance_slope": 32, "ccw_compliance_slope": 32}


def test_the_mx_p1_divisors_are_the_emanuals_pid_law() -> None:
    # e-Manual mx-28.md: Kp = P/8, Kd = D * 4/1000 (per tick, per loop period), on Max Torque 1023.
    mapping = load_servo_model("MX-28", AX_ROBOT).gain_mapping
    per_p = 2.5 * (4096 / (2 * math.pi)) / (2 * 8 * 1023)  # 12 V supply = datasheet voltage
    assert mapping.kp_nm_per_rad(32) == pytest.approx(32 * per_p, rel=1e-12)
    d_over_p = mapping.kd_nms_per_rad(1) / (mapping.kp_nm_per_rad(1) * 0.001)
    assert d_over_p == pytest.approx((4 / 1000) / (1 / 8), rel=1e-12)
    assert (mapping.p_max, mapping.d_max) == (254, 254)


def test_an_ax_slope_is_the_torque_limit_over_that_many_ticks() -> None:
    robot = load_robot(AX_ROBOT)
    stall = 1.5 * 11.1 / 12.0  # 1.5 N·m at 12 V, run at 11.1 V
    assert robot.gains.kp_nm_per_rad == pytest.approx(stall / (32 * AX_RAD_PER_TICK), rel=1e-6)
    assert robot.gains.kd_nms_per_rad == 0.0  # no damping register
    assert robot.gain_writes == SLOPES
    servo = robot.servo
    stiffer = servo.gain_writes(PDGains(robot.gains.kp_nm_per_rad * 2.2))
    assert stiffer == dict.fromkeys(SLOPES, 16)  # the nearest level, both directions alike
    assert servo.gain_writes(PDGains(1e-9)) == dict.fromkeys(SLOPES, 128)
    # The firmware uses the level below a value between levels (e-Manual compliance slope).
    assert servo.gains_from(dict.fromkeys(SLOPES, 40)) == robot.gains
    lopsided = servo.gains_from({"cw_compliance_slope": 16, "ccw_compliance_slope": 64})
    assert lopsided.kp_nm_per_rad == pytest.approx(robot.gains.kp_nm_per_rad * (2 + 0.5) / 2)
    with pytest.raises(KeyError, match="position_p_gain"):
        servo.gains_from({"position_p_gain": 32})


def test_a_lower_torque_limit_softens_the_same_slope(config_dir: Path) -> None:
    robot = load_robot(config_dir / "robots" / "snake12-ax12a.toml")
    path = edit_robot(config_dir, "snake12-ax12a", "[settings]", "[settings]\nmax_torque = 512")
    softer = load_robot(path)
    assert softer.gain_writes == SLOPES
    ratio = softer.gains.kp_nm_per_rad / robot.gains.kp_nm_per_rad
    assert ratio == pytest.approx(512 / 1023)


def test_an_ax_robot_takes_its_stiffness_in_si(config_dir: Path) -> None:
    path = edit_robot(config_dir, "snake12-ax12a", "compliance_slope = 32", "kp_nm_per_rad = 4.0")
    robot = load_robot(path)
    assert robot.gains == PDGains(4.0, 0.0)
    assert robot.gain_writes == dict.fromkeys(SLOPES, 64)  # 4.2 N·m/rad, the nearest level


@pytest.mark.parametrize(
    ("robot", "old", "new", "key", "expected"),
    [
        (
            "snake12-ax12a",
            "compliance_slope = 32",
            "position_p = 32",
            "gains.position_p",
            "AX-12A has a Compliance Slope (compliance_slope",
        ),
        (
            "snake12-ax12a",
            "compliance_slope = 32",
            "compliance_slope = 32\nkd_nms_per_rad = 0.1",
            "gains.kd_nms_per_rad",
            "the damping has no register",
        ),
        (
            "snake12-ax12a",
            "compliance_slope = 32",
            "compliance_slope = 32\nkp_nm_per_rad = 4.0",
            "gains.kp_nm_per_rad",
            "not both",
        ),
        (
            "snake12-ax12a",
            "compliance_slope = 32",
            "compliance_slope = 255",
            "gains.compliance_slope",
            "Compliance Slope register range",
        ),
        (
            "snake12",
            "position_d = 4000",
            "position_d = 4000\ncompliance_slope = 32",
            "gains.compliance_slope",
            "XL430-W250 has Position P/I/D Gain",
        ),
    ],
)
def test_a_gain_of_the_other_kind_of_loop_is_refused_naming_the_key(
    config_dir: Path, robot: str, old: str, new: str, key: str, expected: str
) -> None:
    path = edit_robot(config_dir, robot, old, new)
    with pytest.raises(ConfigError) as info:
        load_robot(path)
    assert (info.value.source, info.value.key) == (str(path), key)
    assert expected in str(info.value)


def test_an_ax_servo_file_with_pd_divisors_is_refused(config_dir: Path) -> None:
    servo_file = config_dir / "servos" / "ax-12a.toml"
    text = servo_file.read_text()
    servo_file.write_text(text.replace("[physics]\n", "[physics]\np_gain_divisor = 256\n", 1))
    with pytest.raises(ConfigError) as info:
        load_robot(config_dir / "robots" / "snake12-ax12a.toml")
    assert (info.value.source, info.value.key) == (str(servo_file), "physics.p_gain_divisor")
    assert "Compliance Slope" in str(info.value)


def test_the_gain_search_refuses_a_compliance_servo_naming_the_gains() -> None:
    robot = load_robot(AX_ROBOT)
    test = GainTest(joints=(0,), gait="serpenoid", gait_s=1.0, step_s=0.5, step_rad=0.1)
    with pytest.raises(ConfigError) as info:
        search_gains(lambda: pytest.fail("no backend is opened"), robot, test, budget=2)
    assert (info.value.source, info.value.key) == (str(AX_ROBOT), "gains")
    assert "compliance_slope" in str(info.value)
