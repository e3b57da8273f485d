"""Obstacle-aided locomotion: on isotropic ground, pegs give lateral undulation what the ground
cannot (Liljebäck, Transeth et al.); the layout and numbers are in docs/terrain.md."""

from __future__ import annotations

import pytest

from snakebot.backends.twin import GroundFriction, TwinBackend
from snakebot.config import load_robot
from tests.integration.twin.terrain_runs import play

ISOTROPIC = GroundFriction(0.3, 0.3)
GAIT = {"amplitude": 0.7}  # serpenoid, phase lag 0.7 rad/joint, 0.5 Hz
LATTICE = "pegs:layout=lattice,spacing_m=0.16,radius_m=0.005,friction=0"


def travel_m(terrain: str | None) -> float:
    robot = load_robot("snake8")
    with TwinBackend(robot, friction=ISOTROPIC, terrain=terrain) as twin:
        return float(play(twin, robot, "serpenoid", 10.0, GAIT).summary["distance_m"])


@pytest.mark.slow
def test_pegs_double_how_far_lateral_undulation_goes_on_isotropic_ground() -> None:
    flat, pegs = travel_m(None), travel_m(LATTICE)
    assert flat > 0.1  # it wriggles forward a little without pegs
    assert pegs >= 2.0 * flat
