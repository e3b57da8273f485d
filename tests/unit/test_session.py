"""The facade (snakebot.connect, Snake, RunSummary, the lazy top-level package) as a script
author meets it: light to import, typed results equal to `snakebot run --json`, options a
backend does not take refused, and the stop policy applied however a `with` block ends."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import snakebot
from snakebot.cli.main import main
from snakebot.errors import BackendOptionError, BackendStateError, GaitError
from snakebot.gaits import SerpenoidGait, save_gait_file
from tests.conftest import edit_robot


def test_import_snakebot_is_light_and_exposes_the_api() -> None:
    code = (
        "import sys, snakebot\n"
        "names = [snakebot.load_robot, snakebot.connect, snakebot.Snake, snakebot.RunSummary,\n"
        "         snakebot.register_gait, snakebot.register_backend, snakebot.gait_names,\n"
        "         snakebot.backend_names, snakebot.robot_names]\n"
        "print([m for m in ('mujoco', 'dynamixel_sdk', 'gymnasium') if m in sys.modules])\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[]"


def test_an_unknown_top_level_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'conect'"):
        snakebot.conect  # type: ignore[attr-defined]  # noqa: B018


def test_run_summary_is_what_run_json_prints(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--json", "--robot", "snake8", "--duration", "2"]) == 0
    printed = json.loads(capsys.readouterr().out)
    with snakebot.connect("snake8", backend="sim") as snake:
        summary = snake.run("serpenoid", duration_s=2)
    assert isinstance(summary, snakebot.RunSummary)
    assert summary.to_dict() == printed  # the twin is deterministic: the same run, field by field
    assert summary.backend == "twin" and summary.distance_m == printed["distance_m"] > 0.05
    with pytest.raises(dataclasses.FrozenInstanceError):
        summary.distance_m = 1.0  # type: ignore[misc]


def test_an_option_the_backend_does_not_take_is_refused_before_anything_opens() -> None:
    with pytest.raises(BackendOptionError, match="the twin backend takes no option 'port'") as err:
        snakebot.connect("snake8", backend="twin", port="/dev/ttyUSB0")
    assert "friction" in str(err.value) and err.value.option == "port"
    with pytest.raises(BackendOptionError, match="dynamixel backend takes no option 'terrain'"):
        snakebot.connect("snake12", backend="dynamixel", terrain="flat")


def test_run_takes_a_name_a_file_or_a_gait_object(tmp_path: Path) -> None:
    path = tmp_path / "gentle.toml"
    save_gait_file(path, "serpenoid", {"amplitude": 0.2}, {})
    with snakebot.connect("snake8") as snake:
        by_file = snake.run(path, duration_s=2)
        by_name = snake.run("serpenoid", duration_s=2, params={"amplitude": 0.2})
        by_object = snake.run(SerpenoidGait(8, amplitude=0.2), duration_s=2)
        with pytest.raises(GaitError, match="drives 12 joints; snake8 has 8"):
            snake.run(SerpenoidGait(12), duration_s=1)
        with pytest.raises(GaitError, match="unknown gait 'slither'"):
            snake.run("slither", duration_s=1)
    assert by_file.gait == "serpenoid" and by_object.gait == "SerpenoidGait"
    for summary in (by_file, by_name, by_object):
        assert summary.max_abs_command_rad == pytest.approx(0.2, abs=1e-6)


def test_leaving_the_block_applies_the_stop_policy_even_on_an_error(config_dir: Path) -> None:
    limp = edit_robot(config_dir, "snake8", 'stop_policy = "hold"', 'stop_policy = "limp"')
    snake = snakebot.connect(limp)
    with pytest.raises(RuntimeError, match="my script failed"), snake:
        snake.send_command(np.full(8, 0.3))
        snake.advance(0.5)
        raise RuntimeError("my script failed")
    assert not snake.connected and not snake.backend.torque_enabled  # limp, as the file says
    with snakebot.connect("snake8") as held:
        held.run("serpenoid", duration_s=1)
    assert not held.connected and held.backend.torque_enabled  # snake8 holds its pose
    with pytest.raises(BackendStateError, match="connect first"):
        held.run("serpenoid", duration_s=1)


def test_prepare_makes_the_backend_without_connecting_it() -> None:
    snake = snakebot.Snake.prepare("snake8", "twin", friction="0.1,0.1")
    assert not snake.connected
    with snake:
        assert snake.connected
        assert snake.read_state().position_rad.shape == (8,)
    assert not snake.connected


def test_load_robot_takes_a_name_a_path_or_a_config() -> None:
    robot = snakebot.load_robot("snake12")
    assert snakebot.load_robot(robot) is robot
    assert snakebot.load_robot(Path(robot.source)).servo_ids == robot.servo_ids
    assert {"snake8", "snake12", "worm"} <= set(snakebot.robot_names())
    assert {"twin", "dynamixel", "softbody"} <= set(snakebot.backend_names())
    assert "sim" not in snakebot.backend_names()
