from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from snakebot.config import load_robot
from snakebot.errors import ConfigError
from snakebot.tuning.config_edit import set_table_values

ROBOT = """\
# a robot
name = "demo"

[gains]                 # Position P/I/D Gain registers
position_p = 640        # default
position_i = 0
position_d = 4000

[twin]
timestep_s = 0.002      # keep me

[[joints]]
servo_id = 1
"""


def test_only_the_values_change_and_every_comment_stays(tmp_path: Path) -> None:
    path = tmp_path / "robot.toml"
    path.write_text(ROBOT)
    set_table_values(path, "gains", {"position_p": 900, "position_d": 3500})
    text = path.read_text()
    assert "position_p = 900        # default\n" in text
    assert "position_d = 3500\n" in text
    assert text.replace("900", "640").replace("3500", "4000") == ROBOT


def test_missing_keys_and_tables_are_added_where_they_belong(tmp_path: Path) -> None:
    path = tmp_path / "robot.toml"
    path.write_text(ROBOT.replace("position_i = 0\n", ""))
    set_table_values(path, "gains", {"position_i": 5})
    set_table_values(path, "twin.servo", {"stiffness_scale": 1.25, "armature_kgm2": 0.003})
    set_table_values(path, "twin.servo", {"stiffness_scale": 1.5})
    data = tomllib.loads(path.read_text())
    assert data["gains"] == {"position_p": 640, "position_d": 4000, "position_i": 5}
    assert data["twin"]["servo"] == {"stiffness_scale": 1.5, "armature_kgm2": 0.003}
    text = path.read_text()
    assert text.index("[twin.servo]") < text.index("[[joints]]")
    assert "timestep_s = 0.002      # keep me" in text


def test_an_unreadable_file_is_a_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError):
        set_table_values(tmp_path / "missing.toml", "gains", {"position_p": 1})


def test_the_loader_reads_fitted_servo_parameters(config_dir: Path) -> None:
    path = config_dir / "robots" / "snake12.toml"
    set_table_values(
        path, "twin.servo", {"stiffness_scale": 1.25, "damping_nms": 0.2, "armature_kgm2": 0.003}
    )
    physics = load_robot(path).servo.physics
    assert (physics.stiffness_scale, physics.damping_nms, physics.armature_kgm2) == (
        1.25,
        0.2,
        0.003,
    )
    set_table_values(path, "twin.servo", {"stiffnes_scale": 1.0})
    with pytest.raises(ConfigError, match=r"twin\.servo\.stiffnes_scale"):
        load_robot(path)
