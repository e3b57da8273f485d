"""Gain tuning converges on the twin, writes the robot file, and tunes a twin-backed bus."""

from __future__ import annotations

import json
import os
import tomllib
from pathlib import Path

import pytest

from snakebot.backends.chain import ServoSettingsWarning
from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.backends.twin import TwinBackend
from snakebot.cli.main import main
from snakebot.config import load_robot
from snakebot.config.schema import GainRegisters
from snakebot.emulation.physics import make_twin_chain
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.emulation.registry import registered
from snakebot.tuning.gain_search import search_gains
from snakebot.tuning.gains import GainTest, evaluate_gains, held
from tests.conftest import edit_robot
from tests.pty_emulator import emulator

QUICK = GainTest(joints=(0, 4), gait="serpenoid", gait_s=2.0, step_s=0.5)


def test_search_on_the_twin_lowers_gait_tracking_error_within_limits() -> None:
    robot = load_robot("snake8")
    result = search_gains(lambda: TwinBackend(robot), robot, QUICK, budget=6, chirps=False)
    assert result.current.gains == robot.gain_registers and result.current.feasible
    assert result.improved and result.best.feasible
    assert result.best.tracking_rms_rad < 0.5 * result.current.tracking_rms_rad
    assert all(step.overshoot <= QUICK.max_overshoot for step in result.best.steps)


def test_overshoot_beyond_the_limit_rejects_a_candidate() -> None:
    robot = load_robot("snake8")
    strict = GainTest(joints=(0,), gait="serpenoid", gait_s=1.0, max_overshoot=-1.0)
    score = evaluate_gains(lambda: TwinBackend(robot), robot, robot.gain_registers, strict)
    assert not score.feasible and "overshoot" in score.reason


def test_cli_writes_the_new_gains_into_the_robot_file(
    config_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = config_dir / "robots" / "snake8.toml"
    before = path.read_text()
    argv = [
        "tune",
        "gains",
        "--robot",
        str(path),
        "--joints",
        "0",
        "--gait-duration",
        "1.5",
        "--budget",
        "4",
        "--report",
        str(config_dir / "report"),
        "--json",
    ]
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert (
        summary["improved"]
        and summary["tracking_rms_after_rad"] < summary["tracking_rms_before_rad"]
    )
    gains = tomllib.loads(path.read_text())["gains"]
    best = summary["best"]
    assert (
        [gains[k] for k in ("position_p", "position_i", "position_d")]
        == [best["position_p"], best["position_i"], best["position_d"]]
        != [640, 0, 4000]
    )
    robot = load_robot(path)
    written = GainRegisters(gains["position_p"], gains["position_i"], gains["position_d"])
    assert robot.gains == robot.servo.gains_of(written)
    assert robot.gain_registers == written
    # The report says both forms: the registers users know and the SI gains the contract took.
    assert (best["kp_nm_per_rad"], best["kd_nms_per_rad"]) == pytest.approx(
        (robot.gains.kp_nm_per_rad, robot.gains.kd_nms_per_rad)
    )
    lines = [
        line
        for line in before.splitlines()
        if "position_p" not in line and "position_d" not in line
    ]
    assert all(line in path.read_text().splitlines() for line in lines)  # comments kept
    assert (config_dir / "report" / "steps.png").is_file()
    assert (config_dir / "report" / "chirp.png").is_file()


def test_cli_keeps_a_robot_file_in_si_and_reports_both_forms(
    config_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = edit_robot(
        config_dir,
        "snake8",
        "position_p = 640\nposition_i = 0\nposition_d = 4000",
        "kp_nm_per_rad = 2.578\nkd_nms_per_rad = 0.1289\nposition_i = 0",
    )
    argv = ["tune", "gains", "--robot", str(path), "--joints", "0", "--gait", "serpenoid"]
    assert main([*argv, "--gait-duration", "1.5", "--budget", "6", "--no-chirp"]) == 0
    out = capsys.readouterr().out
    assert "at P/I/D 640/0/4000 ->" in out and "in SI: kp 2.578 ->" in out
    assert f"written to {path}" in out
    gains = tomllib.loads(path.read_text())["gains"]
    assert set(gains) == {"kp_nm_per_rad", "kd_nms_per_rad", "position_i"}  # one form, still SI
    robot = load_robot(path)
    assert robot.gains.kp_nm_per_rad == gains["kp_nm_per_rad"] != 2.578


def test_search_over_the_emulated_bus_lowers_tracking_error() -> None:
    # The hardware path in virtual time: each candidate's Position P/I/D registers go over the
    # bus, and the twin behind the emulated servos follows them.
    robot = load_robot("snake8")
    chain, _ = make_twin_chain(robot, 1_000_000)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    with registered(chain) as url:
        backend = ServoChainBackend(
            robot,
            port=url,
            baud=1_000_000,
            port_handler_factory=EmulatedPortHandler,
            clock=lambda: chain.now_s,
            sleep=chain.advance,
        )
        with backend:
            test = GainTest(joints=(0,), gait="serpenoid", gait_s=1.0, step_s=0.5, step_rad=0.1)
            result = search_gains(lambda: held(backend), robot, test, budget=6, chirps=False)
            assert chain.servo(1).peek("position_p_gain") == result.scores[-1].gains.position_p
    assert result.current.gains == robot.gain_registers and result.current.feasible
    assert result.improved and result.best.feasible
    assert result.best.tracking_rms_rad < 0.5 * result.current.tracking_rms_rad
    assert result.best.gains.position_p > robot.gain_registers.position_p


@pytest.mark.pty
@pytest.mark.slow
@pytest.mark.skipif(os.name != "posix", reason="pseudo-terminals need POSIX")
def test_cli_tunes_gains_over_a_physics_emulator(
    config_dir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = config_dir / "robots" / "snake8.toml"
    argv = ["tune", "gains", "--robot", str(path), "--joints", "0", "--gait", "serpenoid"]
    argv += ["--gait-duration", "1", "--budget", "6", "--no-chirp", "--json"]
    with emulator("--robot", str(path), "--physics") as emu:
        with pytest.warns(ServoSettingsWarning, match="config apply"):  # factory settings
            code = main([*argv, "--backend", "dynamixel", "--port", emu.port])
        emu.stop()
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["current"]["position_p"] == 640 and summary["improved"]
    assert summary["tracking_rms_after_rad"] < 0.5 * summary["tracking_rms_before_rad"]
    assert load_robot(path).gain_registers.position_p == summary["best"]["position_p"] > 640
