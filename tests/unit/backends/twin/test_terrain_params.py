"""``--terrain NAME:key=value`` parsing: every terrain, its keys and their ranges."""

from __future__ import annotations

import pytest

from snakebot.backends.twin.terrain import (
    BUILT_IN_TERRAINS,
    BodyShape,
    parse_terrain,
    terrain_names,
)
from snakebot.backends.twin.terrain.pegs import Pegs
from snakebot.backends.twin.terrain.rough import Rough
from snakebot.errors import ConfigError

SNAKE8 = BodyShape(8, 0.065, 0.022)


def test_the_suite_has_every_terrain_of_the_issue() -> None:
    built_in = {"flat", "slope", "pegs", "rough", "step", "pipe", "pole", "cliff"}
    assert set(BUILT_IN_TERRAINS) == built_in
    assert set(terrain_names()) >= built_in


@pytest.mark.parametrize("name", BUILT_IN_TERRAINS)
def test_defaults_rebuild_from_their_own_text(name: str) -> None:
    terrain = parse_terrain(name)
    assert parse_terrain(terrain.spec_text()) == terrain


def test_keys_are_typed_and_checked() -> None:
    pegs = parse_terrain("pegs:layout=row,spacing_m=0.15,seed=3")
    assert isinstance(pegs, Pegs)
    assert (pegs.layout, pegs.spacing_m, pegs.seed) == ("row", 0.15, 3)


@pytest.mark.parametrize(
    ("text", "key", "words"),
    [
        ("stairs", "", "flat, slope, pegs"),
        ("pegs:colour=red", "colour", "spacing_m (0.01..5 m)"),
        ("pegs:density=5000", "density", "0.01..2000 1/m^2"),
        ("pegs:layout=grid", "layout", "field|lattice|row"),
        ("pegs:seed=1.5", "seed", "an integer"),
        ("slope:angle_deg=60", "angle_deg", "0..45 deg"),
        ("slope:angle_deg=nan", "angle_deg", "0..45 deg"),
        ("rough:roughness_m=abc", "roughness_m", "0..0.1 m"),
        ("flat:x=1", "x", "none"),
        ("cliff:edge_m=0.01", "edge_m", "flat top"),
    ],
)
def test_bad_text_names_the_key_and_what_it_accepts(text: str, key: str, words: str) -> None:
    with pytest.raises(ConfigError) as caught:
        parse_terrain(text)
    assert caught.value.source == "terrain"  # the library names the option, the CLI its flag
    assert caught.value.key == key
    assert words in str(caught.value)


def test_a_pipe_too_narrow_for_the_links_is_refused() -> None:
    with pytest.raises(ConfigError, match=r"inner_diameter_m.*2\.2 link radii"):
        parse_terrain("pipe:inner_diameter_m=0.04").check(SNAKE8)


def test_peg_layouts_are_seeded_and_clear_of_the_body() -> None:
    field = Pegs(seed=4)
    first, again = field.centres(SNAKE8), field.centres(SNAKE8)
    assert first.shape[0] > 100 and (first == again).all()
    assert not (Pegs(seed=5).centres(SNAKE8) == first).all()
    for layout in ("field", "lattice", "row"):
        centres = Pegs(layout=layout).centres(SNAKE8)
        along = centres[:, 0].clip(-SNAKE8.body_length_m, 0.0)
        gap = ((centres[:, 0] - along) ** 2 + centres[:, 1] ** 2) ** 0.5
        assert gap.min() >= Pegs().radius_m + SNAKE8.radius_m, layout


def test_rough_heights_have_the_asked_roughness_and_a_flat_field_is_flat() -> None:
    heights = Rough(roughness_m=0.01, seed=1).heights()
    assert heights.std() == pytest.approx(0.01)
    assert abs(heights.mean()) < 1e-9
    assert not (heights == Rough(roughness_m=0.01, seed=2).heights()).all()
    assert not Rough(roughness_m=0.0).heights().any()
