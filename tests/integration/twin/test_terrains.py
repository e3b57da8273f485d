"""Every terrain builds for the shipped robots, a gait runs on it without a physics error, and
the snake starts where the terrain says (inside the pipe, before the step, beside the pole)."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.backends.twin.model_builder import link_name
from snakebot.backends.twin.terrain import BUILT_IN_TERRAINS, parse_terrain
from snakebot.config import load_robot
from tests.integration.twin.terrain_runs import play

GAITS = {"snake8": "serpenoid", "snake12": "lateral_undulation"}


def link_positions(twin: TwinBackend) -> np.ndarray:
    """Module centres (L, 3) in m, head first."""
    ids = [twin.model.body(link_name(i)).id for i in range(twin.robot.link_count)]
    return np.asarray(twin.data.xipos[ids]).copy()


@pytest.mark.parametrize("robot_name", sorted(GAITS))
@pytest.mark.parametrize("terrain", sorted(BUILT_IN_TERRAINS))
def test_a_gait_runs_on_every_terrain_without_physics_warnings(
    robot_name: str, terrain: str
) -> None:
    robot = load_robot(robot_name)
    twin = TwinBackend(robot, terrain=terrain)
    with twin:
        result = play(twin, robot, GAITS[robot_name], duration_s=1.5)
        warnings = {
            mujoco.mjtWarning(i).name: int(twin.data.warning[i].number)
            for i in range(len(twin.data.warning))
            if twin.data.warning[i].number
        }
        positions = link_positions(twin)
    assert not result.interrupted
    assert warnings == {}
    assert np.isfinite(positions).all()
    assert positions[:, 2].min() > -0.2  # nobody fell through the ground


def test_the_snake_starts_inside_the_pipe_and_stays_there() -> None:
    robot = load_robot("snake8")
    pipe = parse_terrain("pipe:inner_diameter_m=0.12")
    with TwinBackend(robot, terrain=pipe) as twin:
        play(twin, robot, "serpenoid", duration_s=2.0)
        positions = link_positions(twin)
    axis_z = 0.06 + 0.01  # inner radius + wall
    radial = np.hypot(positions[:, 1], positions[:, 2] - axis_z)
    assert radial.max() < 0.06 - robot.link.radius_m + 2e-3


def test_the_step_is_in_front_of_the_head_and_the_pole_beside_the_body() -> None:
    robot = load_robot("snake8")
    with TwinBackend(robot, terrain="step:height_m=0.05,distance_m=0.1") as twin:
        step = twin.model.geom("step")
        face = step.pos[0] - step.size[0]
        nose = twin.data.xpos[twin.model.body(link_name(0)).id]  # the head capsule's front end
        assert face - nose[0] == pytest.approx(0.1 + robot.link.radius_m)
        assert nose[2] == pytest.approx(robot.link.radius_m, abs=2e-3)  # on the floor
    with TwinBackend(robot, terrain="pole:diameter_m=0.1") as twin:
        pole = np.asarray(twin.model.geom("pole").pos)
        positions = link_positions(twin)
        gap = np.hypot(*(positions[:, :2] - pole[:2]).T).min() - 0.05 - robot.link.radius_m
        assert 0 < gap < 0.02


def test_on_a_slope_the_snake_lies_on_the_incline() -> None:
    robot = load_robot("snake8")
    with TwinBackend(robot, terrain="slope:angle_deg=15") as twin:
        twin.advance(0.2)
        positions = link_positions(twin)
    # The floor rises towards +x: height above the tilted plane is the capsule radius.
    normal = np.array([-math.sin(math.radians(15)), 0.0, math.cos(math.radians(15))])
    height = positions @ normal
    assert height == pytest.approx(np.full(len(positions), robot.link.radius_m), abs=2e-3)
    assert positions[0, 2] > positions[-1, 2] + 0.1  # head uphill


def test_on_rough_ground_the_snake_rests_on_the_field() -> None:
    robot = load_robot("snake8")
    rough = parse_terrain("rough:roughness_m=0.01,seed=3")
    with TwinBackend(robot, terrain=rough) as twin:
        twin.advance(0.5)
        positions = link_positions(twin)
        assert twin.data.ncon > 0
        touching = {twin.model.geom(int(g)).name for pair in twin.data.contact.geom for g in pair}
    assert "rough" in touching and "floor" not in touching
    assert np.abs(positions[:, 2]).max() < 0.05 + robot.link.radius_m
