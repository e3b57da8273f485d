"""`snakebot run --torque-limit NM`: every servo capped at NM while it follows the gait (the
twin's actuators; current-based position control on servos that have it), a bad value or a
servo without the mode refused before anything moves (exit 2)."""

from __future__ import annotations

import json

import pytest

from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.emulation import make_chain_for_ids, registered


def _summary(capsys: pytest.CaptureFixture[str], *argv: str) -> dict[str, object]:
    assert main(["run", "--duration", "2", "--json", *argv]) == 0
    summary: dict[str, object] = json.loads(capsys.readouterr().out)
    return summary


def test_the_twin_pushes_no_harder_than_the_cap_and_still_swims(
    capsys: pytest.CaptureFixture[str],
) -> None:
    free = _summary(capsys)
    capped = _summary(capsys, "--torque-limit", "0.2")
    assert "torque_limit_nm" not in free and capped["torque_limit_nm"] == 0.2
    assert free["peak_servo_torque_nm"] > 0.25  # type: ignore[operator]
    assert capped["peak_servo_torque_nm"] <= 0.2 * 1.05  # type: ignore[operator]
    assert capped["distance_m"] > 0.5 * free["distance_m"]  # type: ignore[operator]
    assert capped["tracking_rms_rad"] > free["tracking_rms_rad"]  # type: ignore[operator]


@pytest.mark.parametrize("value", ["0", "-1", "nan", "1.5"])
def test_a_cap_outside_zero_to_stall_is_bad_usage(
    capsys: pytest.CaptureFixture[str], value: str
) -> None:
    assert main(["run", "--duration", "1", "--torque-limit", value]) == 2
    err = capsys.readouterr().err
    assert "--torque-limit" in err and "1.4 (the XL430-W250's stall torque)" in err, err


def test_servos_without_current_based_position_are_refused_before_anything_moves(
    capsys: pytest.CaptureFixture[str],
) -> None:
    robot = load_robot("snake8")  # XL430-W250: no Operating Mode 5
    chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, robot.bus.baud)
    with registered(chain) as url:
        argv = ["run", "--robot", "snake8", "--backend", "dynamixel", "--port", url]
        argv += ["--torque-limit", "0.5"]
        code = main([*argv, "--duration", "1"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "--torque-limit" in err and "XL430-W250 servos" in err and "Operating Mode 5" in err
    assert not any(servo.torque_enabled for servo in chain.servos)


def test_the_soft_body_has_no_torque_to_cap(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["run", "--robot", "worm", "--duration", "1", "--torque-limit", "0.5"])
    err = capsys.readouterr().err
    assert code == 2 and "--torque-limit" in err and "current-based position" in err, err
