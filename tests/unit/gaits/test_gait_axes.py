"""Gaits declare the joint axes they need; a robot with other axes is warned or refused."""

from __future__ import annotations

import json
import subprocess
import sys
import warnings

import pytest

from snakebot.config import load_robot
from snakebot.errors import GaitAxesWarning, GaitError
from snakebot.gaits import check_joint_axes, gait_names, get_spec

SNAKE8 = [j.axis for j in load_robot("snake8").joints]  # all yaw
SNAKE12 = [j.axis for j in load_robot("snake12").joints]  # yaw, pitch, yaw, ...


@pytest.mark.parametrize("name", ["rolling", "turn_in_place", "sidewinding", "linear_progression"])
def test_cmu_presets_that_need_a_pitch_wave_are_refused_on_the_all_yaw_snake8(name: str) -> None:
    # The audit: on snake8 "turn_in_place" went straight 7.2 m and "rolling" did not roll,
    # with no warning.
    with pytest.raises(
        GaitError,
        match=rf"gait '{name}' needs .*pitch on odd joints.*snake8 has "
        r"other axes on joints 1 \(yaw\), 3 \(yaw\)",
    ):
        check_joint_axes(name, SNAKE8, "snake8")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert check_joint_axes(name, SNAKE12, "snake12") is None


def test_a_gait_on_the_wrong_axes_that_still_moves_is_a_warning() -> None:
    with pytest.warns(GaitAxesWarning, match="'serpenoid' needs yaw on every joint.*snake12"):
        text = check_joint_axes("serpenoid", SNAKE12, "snake12")
    assert text is not None and "joints 1 (pitch), 3 (pitch)" in text
    with pytest.warns(GaitAxesWarning, match="'compound' needs"):
        check_joint_axes("compound", SNAKE8, "snake8")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert check_joint_axes("serpenoid", SNAKE8) is None
        assert check_joint_axes("lateral_undulation", SNAKE8) is None
        assert check_joint_axes("lateral_undulation", SNAKE12) is None
        assert check_joint_axes("keyframes", SNAKE12) is None


def test_every_gait_says_what_axes_it_needs_in_words() -> None:
    for name in gait_names():
        assert get_spec(name).axes.describe()


def test_the_cli_refuses_rolling_on_snake8_before_anything_moves() -> None:
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "snakebot",
            "run",
            "--robot",
            "snake8",
            "--gait",
            "rolling",
            "--duration",
            "1",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 1
    assert "gait 'rolling' needs" in done.stderr and "snake8" in done.stderr
    assert done.stdout == ""


def test_the_gait_listing_says_what_axes_a_gait_needs(capsys: pytest.CaptureFixture[str]) -> None:
    from snakebot.cli.main import main

    assert main(["gaits", "rolling"]) == 0
    assert "joint axes: needs yaw on even joints" in capsys.readouterr().out
    assert main(["gaits", "--json"]) == 0
    listing = {g["name"]: g for g in json.loads(capsys.readouterr().out)}
    assert listing["serpenoid"]["axes"] == {"even": "yaw", "odd": "yaw", "required": False}
    assert listing["rolling"]["axes"]["required"] is True
