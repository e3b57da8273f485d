"""A robot MuJoCo refuses to compile is a ConfigError naming the robot file, not a bug.

The loader's ranges keep such values out of robot files; a RobotConfig built in code (as
researchers do) meets MuJoCo's own checks, which must end the same way.
"""

from __future__ import annotations

import dataclasses

import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.model_builder import build_model
from snakebot.config import load_robot
from snakebot.errors import ConfigError


@pytest.mark.parametrize(
    "link",
    [{"mass_kg": 1e308}, {"mass_kg": 1e-300}, {"radius_m": 1e-300}, {"length_m": 1e308}],
    ids=["mass 1e308", "mass 1e-300", "radius 1e-300", "length 1e308"],
)
def test_a_link_mujoco_refuses_names_the_robot_file_and_table(link: dict[str, float]) -> None:
    base = load_robot("snake8")
    robot = dataclasses.replace(base, link=dataclasses.replace(base.link, **link))
    with pytest.raises(ConfigError, match="MuJoCo cannot compile the twin: mass and") as info:
        build_model(robot)
    assert (info.value.source, info.value.key) == (str(base.source), "link")
    with pytest.raises(ConfigError, match="link0"):
        TwinBackend(robot).connect()


def test_the_shipped_robots_compile() -> None:
    for name in ("snake8", "snake12"):
        model, _ = build_model(load_robot(name))
        assert model.nbody > 8
