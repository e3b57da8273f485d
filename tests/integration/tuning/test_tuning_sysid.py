"""sysid recovers the servo parameters a twin log was made with, and writes them."""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.tuning.config_edit import set_table_values
from snakebot.tuning.excitation import chirp_plan, record
from snakebot.tuning.sysid import ServoFit, fit_servo, load_log

TRUE = (1.25, 0.8, 1.5)  # stiffness, damping and armature, relative to the shipped values


def test_fit_recovers_stiffness_damping_and_armature(tmp_path: Path) -> None:
    robot = load_robot("snake12")
    nominal = ServoFit.of(robot)
    truth = nominal.scaled(("stiffness", "damping", "armature"), TRUE)
    log_path = tmp_path / "lift.csv"
    with TwinBackend(truth.apply(robot)) as twin:
        plan = chirp_plan(robot, twin.read_state().position_rad, 1, 0.5, duration_s=2.0)
        assert record(twin, robot, plan, log_path) == len(plan)
    result = fit_servo(robot, [load_log(log_path, robot)])
    for field in ("stiffness_scale", "damping_nms", "armature_kgm2"):
        assert getattr(result.after, field) == pytest.approx(getattr(truth, field), rel=0.02)
    assert result.rms_after_rad < 0.01 * result.rms_before_rad


def test_cli_records_fits_and_writes_twin_servo(
    config_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    robots = config_dir / "robots"
    truth_path = robots / "truth.toml"
    shutil.copy(robots / "snake12.toml", truth_path)
    with truth_path.open("a") as handle:
        handle.write("\n[twin.servo]\nstiffness_scale = 0.8\narmature_kgm2 = 0.0025\n")
    log_path = config_dir / "lift.csv"
    assert (
        main(["sysid", "--robot", str(truth_path), "--record", str(log_path), "--duration", "1.5"])
        == 0
    )
    capsys.readouterr()
    target = robots / "snake12.toml"
    assert (
        main(
            [
                "sysid",
                "--robot",
                str(target),
                str(log_path),
                "--params",
                "stiffness,armature",
                "--report",
                str(config_dir / "report"),
                "--json",
            ]
        )
        == 0
    )
    summary = json.loads(capsys.readouterr().out)
    assert summary["after"]["stiffness_scale"] == pytest.approx(0.8, rel=0.02)
    assert summary["tracking_rms_after_rad"] < summary["tracking_rms_before_rad"]
    physics = load_robot(target).servo.physics
    assert physics.stiffness_scale == pytest.approx(0.8, rel=0.02)
    assert physics.armature_kgm2 == pytest.approx(0.0025, rel=0.02)
    assert (config_dir / "report" / "replay.png").is_file()


def test_cli_recovers_an_actuator_delay_and_writes_it(
    config_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    robots = config_dir / "robots"
    truth_path = robots / "truth.toml"
    shutil.copy(robots / "snake12.toml", truth_path)
    with truth_path.open("a") as handle:
        handle.write("\n[twin.servo]\nstiffness_scale = 1.25\nactuator_delay_s = 0.015\n")
    log_path = config_dir / "lift.csv"
    record_args = ["--robot", str(truth_path), "--record", str(log_path), "--duration", "1.0"]
    assert main(["sysid", *record_args]) == 0
    capsys.readouterr()
    target = robots / "snake12.toml"
    fit_args = ["--robot", str(target), str(log_path), "--params", "stiffness,delay", "--json"]
    assert main(["sysid", *fit_args]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["before"]["actuator_delay_s"] == 0.0
    # The log is the twin's own, so the fit is exact to the solver's tolerance (measured: 1e-8 s
    # off); a tenth of the 2 ms timestep still tells the delay from its whole-step neighbours.
    assert summary["after"]["actuator_delay_s"] == pytest.approx(0.015, abs=2e-4)
    assert summary["after"]["stiffness_scale"] == pytest.approx(1.25, rel=0.01)
    assert summary["tracking_rms_after_rad"] < 0.01 * summary["tracking_rms_before_rad"]
    physics = load_robot(target).servo.physics
    assert physics.actuator_delay_s == pytest.approx(0.015, abs=2e-4)


def test_fit_tells_which_p_gain_divisor_the_servo_has(config_dir: Path) -> None:
    # bam measured 256 on an XL330; the e-Manual's KPP = P/128 suggests 128. A log made by a
    # servo with 128 is fitted from the shipped 256.
    robot = load_robot("snake12")
    nominal = ServoFit.of(robot)
    assert nominal.p_gain_divisor == 256.0
    truth = dataclasses.replace(nominal, p_gain_divisor=128.0)
    # The servos hold the same registers; under 128 they mean twice the stiffness (SI path).
    truth_robot = truth.apply(robot)
    assert truth_robot.gain_registers == robot.gain_registers
    assert truth_robot.gains.kp_nm_per_rad == pytest.approx(2 * robot.gains.kp_nm_per_rad)
    log_path = config_dir / "lift.csv"
    with TwinBackend(truth_robot) as twin:
        plan = chirp_plan(robot, twin.read_state().position_rad, 1, 0.5, duration_s=2.0)
        record(twin, robot, plan, log_path)
    result = fit_servo(robot, [load_log(log_path, robot)], ("p_divisor",))
    assert result.after.p_gain_divisor == pytest.approx(128.0, rel=0.02)
    assert result.after.report(robot)["p_gain_divisor"] == result.after.p_gain_divisor
    # Written to [twin.servo] as the CLI does, the robot file loads to the fitted SI gains.
    target = config_dir / "robots" / "snake12.toml"
    set_table_values(target, "twin.servo", {"p_gain_divisor": result.after.p_gain_divisor})
    reloaded = load_robot(target)
    assert reloaded.gains == result.after.apply(robot).gains
    assert reloaded.gain_registers == robot.gain_registers
