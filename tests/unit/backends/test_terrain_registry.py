"""The terrain registry: built-ins by name, runtime registrations, generated help, and one
``parse_terrain`` that reads it (plugins' entry points: tests/plugins)."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass

import mujoco
import pytest

from snakebot.backends.terrains import (
    BUILT_IN_TERRAINS,
    TERRAINS,
    get_terrain,
    register_terrain,
    terrain_help,
    terrain_names,
    terrain_origin,
)
from snakebot.backends.twin.terrain import BodyShape, Cliff, Terrain, parse_terrain
from snakebot.backends.twin.terrain.base import add_obstacle
from snakebot.backends.twin.terrain.params import param
from snakebot.backends.twin.terrain.pegs import Pegs
from snakebot.errors import ConfigError, TerrainError


@dataclass(frozen=True)
class Wall(Terrain):
    """A wall ahead of the head, for these tests."""

    name = "wall"
    summary = "a wall ahead"

    distance_m: float = param(0.3, 0.05, 5.0, "m", "head to the wall")

    def add_to(self, spec: mujoco.MjSpec, body: BodyShape) -> None:
        add_obstacle(
            spec.worldbody,
            name="wall",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            pos=[self.distance_m, 0.0, 0.05],
            size=[0.01, 1.0, 0.05],
        )


@pytest.fixture
def wall() -> Iterator[type[Wall]]:
    register_terrain(Wall)
    try:
        yield Wall
    finally:
        TERRAINS.unregister("wall")


def test_built_ins_come_first_in_their_order_and_load_by_name() -> None:
    assert terrain_names()[: len(BUILT_IN_TERRAINS)] == list(BUILT_IN_TERRAINS)
    assert get_terrain("pegs") is Pegs and get_terrain("cliff") is Cliff
    assert str(terrain_origin("cliff")) == "built-in"


def test_a_registered_terrain_is_parsed_listed_and_in_the_help(wall: type[Wall]) -> None:
    terrain = parse_terrain("wall:distance_m=0.5", "--terrain")
    assert isinstance(terrain, Wall) and terrain.distance_m == 0.5
    assert "wall" in terrain_names() and str(terrain_origin("wall")) == "registered at runtime"
    listed = terrain_help().split(", with key=value")[0].split(", ")
    assert listed[0] == "flat (default)" and listed[-1] == "wall"  # after built-ins, plugins
    with pytest.raises(ConfigError, match=r"--terrain: distance_m: expected 0.05..5 m"):
        parse_terrain("wall:distance_m=9", "--terrain")


def test_taken_names_and_non_terrains_are_refused_and_unregister_restores(
    wall: type[Wall],
) -> None:
    with pytest.raises(TerrainError, match="wall"):
        register_terrain(Wall)
    register_terrain(Wall, replace=True)  # the one you want, on purpose

    @dataclass(frozen=True)
    class Flat(Terrain):
        name = "flat"

    with pytest.raises(TerrainError, match="flat"):
        register_terrain(Flat)
    assert get_terrain("flat") is not Flat  # a built-in name stays the built-in
    with pytest.raises(TerrainError, match="Terrain subclass"):
        register_terrain(dict)  # type: ignore[arg-type]
    TERRAINS.unregister("wall")
    with pytest.raises(ConfigError, match=r"terrain: expected one of flat, slope"):
        parse_terrain("wall")
    register_terrain(Wall)  # for the fixture's unregister


def test_an_unknown_terrain_names_the_option_and_the_known_ones() -> None:
    with pytest.raises(ConfigError) as caught:
        parse_terrain("stairs:height_m=0.1", "--terrain")
    assert caught.value.source == "--terrain"
    assert "expected one of flat, slope, pegs, rough, step, pipe, pole, cliff" in str(caught.value)
    with pytest.raises(TerrainError, match=r"did you mean 'slope'"):
        get_terrain("slop")


def test_listing_the_terrains_imports_no_terrain_and_no_mujoco() -> None:
    code = (
        "import sys; from snakebot.backends.terrains import terrain_help, terrain_names; "
        "names = terrain_names(); terrain_help(); "
        "print(names[:8], 'mujoco' in sys.modules, "
        "any(m.startswith('snakebot.backends.twin') for m in sys.modules))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True
    )
    assert out.stdout.split("]")[1].split() == ["False", "False"], out.stdout
