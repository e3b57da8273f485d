"""`snakebot run --comply`: gait-based compliance per run, its figures in the summary, and a
clear refusal on servos that cannot measure current (a flag these servos cannot serve: exit 2,
nothing energised)."""

from __future__ import annotations

import json

import pytest

from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.emulation import make_chain_for_ids, registered


def test_comply_on_the_twin_reports_how_far_the_gait_gave_way(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["run", "--comply", "--duration", "2", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    compliance = summary["compliance"]
    assert compliance["windows"] == 4
    # Flat ground: locomotion's torque stays inside the dead band, so the gait is the gait.
    assert compliance["lowest_amplitude_scale"] == [1.0] * 4
    assert summary["servo_stall_s"] == 0.0  # every run on torque-sensing servos has it
    assert 0.05 < summary["peak_servo_torque_nm"] < 1.5
    assert summary["max_abs_command_rad"] == pytest.approx(0.4, abs=1e-6)


def test_without_comply_the_summary_has_no_compliance(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--duration", "0.5", "--json"]) == 0
    assert "compliance" not in json.loads(capsys.readouterr().out)


def test_comply_on_servos_without_current_sensing_is_refused_before_anything_moves(
    capsys: pytest.CaptureFixture[str],
) -> None:
    robot = load_robot("snake12-ax12a")  # AX-12A: Present Load, no Present Current
    chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, robot.bus.baud)
    goals = [servo.peek("goal_position") for servo in chain.servos]
    with registered(chain) as url:
        code = main(
            [
                "run",
                "--comply",
                "--robot",
                "snake12-ax12a",
                "--backend",
                "dynamixel",
                "--port",
                url,
                "--duration",
                "1",
            ]
        )
    err = capsys.readouterr().err
    assert code == 2, err
    assert "--comply" in err and "Present Current" in err and "AX-12A servos" in err, err
    assert "Traceback" not in err
    assert not any(servo.torque_enabled for servo in chain.servos)
    assert [servo.peek("goal_position") for servo in chain.servos] == goals


def test_comply_phase_lets_the_phase_yield_too(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["run", "--comply", "--terrain", "pegs:density=100,seed=1", "--duration", "3"]
    assert main([*argv, "--json"]) == 0
    without = json.loads(capsys.readouterr().out)["compliance"]
    assert main([*argv, "--json", "--comply-phase", "2"]) == 0
    with_phase = json.loads(capsys.readouterr().out)["compliance"]
    assert without["largest_phase_rad"] == [0.0] * 4  # off unless asked for
    assert max(with_phase["largest_phase_rad"]) > 0.01, with_phase


@pytest.mark.parametrize(
    ("flags", "says"),
    [
        (["--comply-phase", "2"], "goes with --comply"),
        (["--comply", "--comply-phase", "-1"], ">= 0"),
    ],
)
def test_comply_phase_misused_is_bad_usage(
    capsys: pytest.CaptureFixture[str], flags: list[str], says: str
) -> None:
    assert main(["run", "--duration", "1", *flags]) == 2
    assert says in capsys.readouterr().err
