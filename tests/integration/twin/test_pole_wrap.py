"""A start wrapped on the pole: the coil lands around the pole, head end up, and the tuned
rolling helix climbs more than one body length from it (tools/bench_pole_climb.py, docs/twin.md).

Measured on snake12, pole 0.1 m: omega -2.2 rad/s, pitch 0.03 m/rad, pole_radius_m 0.052 climbs
0.99 m (1.17 body lengths) in 15 s at a steady 0.066 m/s; the stock omega -pi/2, pitch 0.04
climbs 0.03 m/s.
"""

from __future__ import annotations

import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.model_builder import link_name
from snakebot.backends.twin.pole_wrap import wrap_on_pole
from snakebot.config import load_robot
from snakebot.errors import ConfigError
from snakebot.gaits import make_gait
from tools.bench_pole_climb import climb_heights

POLE = "pole:diameter_m=0.1,height_m=1.5"
CLIMB = {"omega": -2.2, "pitch_m_per_rad": 0.03, "pole_radius_m": 0.052}


def test_the_wrapped_start_coils_the_body_around_the_pole_head_end_up() -> None:
    robot = load_robot("snake12")
    gait = make_gait("rolling_helix", robot.joint_count, CLIMB)
    with TwinBackend(robot, terrain=POLE) as twin:
        wrap_on_pole(twin, gait.targets(0.0))
        pole = np.asarray(twin.model.geom("pole").pos)[:2]
        ids = [twin.model.geom(f"{link_name(i)}_geom").id for i in range(robot.link_count)]
        centres = np.asarray(twin.data.geom_xpos[ids])
        np.testing.assert_allclose(twin.read_state().position_rad, gait.targets(0.0), atol=1e-9)
    across = np.hypot(*(centres[:, :2] - pole).T)
    # Every module sits one pole radius + one module radius (0.072 m) from the pole's axis.
    assert np.all(np.abs(across - 0.05 - robot.link.radius_m) < 0.01), across
    assert centres[0, 2] > centres[-1, 2] + 0.1  # head end up
    assert centres[:, 2].min() - robot.link.radius_m == pytest.approx(0.005, abs=1e-6)


def test_the_wrapped_start_refuses_a_terrain_without_a_pole() -> None:
    robot = load_robot("snake12")
    with TwinBackend(robot) as twin, pytest.raises(ConfigError, match="pole"):
        wrap_on_pole(twin, np.zeros(robot.joint_count))


def test_the_rolling_helix_climbs_more_than_one_body_length_up_the_pole() -> None:
    heights, body_length = climb_heights("snake12", POLE, CLIMB, 15.0, 1.0)
    assert heights[-1] - heights[0] > body_length
    # Steadily: every second of the climb gains height (0.066 m/s measured).
    assert np.all(np.diff(heights[1:]) > 0.03), heights
