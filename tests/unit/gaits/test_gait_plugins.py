"""Gaits from plugins and from register_gait: listed with their origin, built, tuned, saved;
clashing and broken plugins; what a GaitSpec must declare to be accepted."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path

import numpy as np
import pytest

from snakebot.errors import GaitError
from snakebot.gaits import (
    GAITS,
    Gait,
    GaitSpec,
    ParamSpec,
    ParamValues,
    SerpenoidGait,
    gait_names,
    gait_origin,
    get_spec,
    load_gait_file,
    make_gait,
    parse_set_options,
    register_gait,
    save_gait_file,
)
from snakebot.gaits.base import FloatArray
from snakebot.gaits.serpenoid import SPEC as SERPENOID
from snakebot.plugins import PluginWarning
from snakebot.tuning.space import build_space, tuning_base
from tests.plugins.install import install_project, on_path, write_dist_info, write_module

EXAMPLE_ORIGIN = "plugin snakebot-example-plugin 0.1.0"


def _gentle(joint_count: int, p: ParamValues, _lower: FloatArray, _upper: FloatArray) -> Gait:
    return SerpenoidGait(joint_count, amplitude=p.number("amplitude"), omega=p.number("omega"))


def _gentle_start(joint_count: int, fixed: Mapping[str, object]) -> dict[str, object]:
    return {"amplitude": 0.25, **fixed}


GENTLE = GaitSpec(
    "gentle_wave",
    "A slow, small serpenoid defined in a script.",
    (
        ParamSpec("amplitude", "rad", 0.2, "joint amplitude", bounds=(0.1, 0.3), tunable=True),
        ParamSpec("omega", "rad/s", 1.0, "frequency", bounds=(0.5, 2.0), tunable=True),
    ),
    _gentle,
    tuning_start=_gentle_start,
)


@pytest.fixture
def gentle() -> Iterator[GaitSpec]:
    register_gait(GENTLE)
    yield GENTLE
    GAITS.unregister(GENTLE.name)


@pytest.fixture
def site(tmp_path: Path) -> Iterator[Path]:
    folder = tmp_path / "site"
    folder.mkdir()
    install_project(folder)
    with on_path(folder):
        yield folder


def test_a_gait_registered_at_runtime_is_built_tuned_and_saved(
    gentle: GaitSpec, tmp_path: Path
) -> None:
    assert "gentle_wave" in gait_names()
    assert str(gait_origin("gentle_wave")) == "registered at runtime"
    params = parse_set_options("gentle_wave", ["omega=pi/4"])
    gait = make_gait("gentle_wave", 6, params)
    expected = SerpenoidGait(6, amplitude=0.2, omega=math.pi / 4).targets(np.linspace(0, 2, 5))
    np.testing.assert_array_equal(gait.targets(np.linspace(0, 2, 5)), expected)
    space = build_space("gentle_wave", tuning_base("gentle_wave", 6, {}))
    assert space.names == ("amplitude", "omega")
    assert space.lower.tolist() == [0.1, 0.5] and space.upper.tolist() == [0.3, 2.0]
    assert space.start().tolist() == [0.25, 1.0]  # the gait's own tuning start
    path = tmp_path / "gentle.toml"
    save_gait_file(path, "gentle_wave", {"omega": 1.5})
    assert load_gait_file(path)[:2] == ("gentle_wave", {"omega": 1.5})


def test_register_gait_refuses_a_taken_name_unless_replacing() -> None:
    mine = GaitSpec("serpenoid", "my serpenoid", GENTLE.params, _gentle)
    with pytest.raises(GaitError, match=r"'serpenoid' is already registered \(built-in\)"):
        register_gait(mine)
    with pytest.raises(GaitError, match="register_gait expects a GaitSpec, got str"):
        register_gait("serpenoid")  # type: ignore[arg-type]
    register_gait(mine, replace=True)
    try:
        assert get_spec("serpenoid") is mine
        assert str(gait_origin("serpenoid")) == "registered at runtime"
    finally:
        GAITS.unregister("serpenoid")
    assert get_spec("serpenoid") is SERPENOID


def test_an_installed_plugin_gait_is_listed_with_its_distribution_and_builds(site: Path) -> None:
    assert "standing_wave" in gait_names()
    origin = gait_origin("standing_wave")
    assert str(origin) == EXAMPLE_ORIGIN
    assert origin.entry_point == "standing_wave = snakebot_example_plugin.standing_wave:SPEC"
    poses = make_gait("standing_wave", 8, {"amplitude": 0.4}).targets(np.linspace(0.1, 0.9, 9))
    shape = 0.4 * np.cos(np.pi / 4 * np.arange(8))
    ratios = poses / shape  # a standing wave: every joint is the same sine, scaled
    np.testing.assert_allclose(ratios, np.repeat(ratios[:, :1], 8, axis=1), atol=1e-9)
    space = build_space("standing_wave", tuning_base("standing_wave", 8, {}))
    assert space.names == ("amplitude", "omega")
    assert space.upper.tolist() == [1.0, 4 * math.pi]


def test_a_broken_plugin_leaves_the_other_gaits_working(site: Path) -> None:
    write_module(site, "snakebot_broken_plugin", "import snakebot_missing_dependency\n")
    write_dist_info(
        site,
        "snakebot-broken-plugin",
        "0.0.1",
        {"snakebot.gaits": {"broken_wave": "snakebot_broken_plugin:SPEC"}},
    )
    GAITS.refresh()
    assert "broken_wave" in gait_names()
    assert make_gait("serpenoid", 8).joint_count == 8
    assert make_gait("standing_wave", 8).joint_count == 8
    with pytest.warns(PluginWarning) as caught:
        listed = GAITS.load_all()
    assert "broken_wave" not in listed and {"serpenoid", "standing_wave"} <= set(listed)
    message = str(caught[0].message)
    assert "snakebot-broken-plugin 0.0.1" in message
    assert "broken_wave = snakebot_broken_plugin:SPEC" in message
    with pytest.raises(GaitError, match="snakebot_missing_dependency"):
        make_gait("broken_wave", 8)


def test_a_plugin_spec_must_carry_its_entry_point_name(site: Path) -> None:
    write_dist_info(
        site,
        "snakebot-misnamed-plugin",
        "1.0",
        {"snakebot.gaits": {"wave": "snakebot_example_plugin.standing_wave:SPEC"}},
    )
    GAITS.refresh()
    with pytest.raises(GaitError, match="GaitSpec is named 'standing_wave'; the names must match"):
        get_spec("wave")


def test_plugins_cannot_replace_builtins_and_clashing_plugins_are_refused(site: Path) -> None:
    write_dist_info(
        site,
        "snakebot-rival-plugin",
        "2.0",
        {
            "snakebot.gaits": {
                "serpenoid": "snakebot_example_plugin.standing_wave:SPEC",
                "standing_wave": "snakebot_example_plugin.standing_wave:SPEC",
            }
        },
    )
    GAITS.refresh()
    with pytest.warns(PluginWarning) as caught:
        assert get_spec("serpenoid") is SERPENOID
    messages = " | ".join(str(w.message) for w in caught)
    assert "snakebot-rival-plugin 2.0" in messages and "built-in is kept" in messages
    assert "offered by 2 plugins" in messages
    with pytest.raises(GaitError) as info:
        make_gait("standing_wave", 8)
    assert "snakebot-rival-plugin 2.0" in str(info.value)
    assert "snakebot-example-plugin 0.1.0" in str(info.value)


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: ParamSpec("mode", "", "a", "text", bounds=(0, 1)), "bounds must be finite"),
        (lambda: ParamSpec("flag", "0/1", 0.0, "flag", bounds=(0, 1)), "bounds must be finite"),
        (lambda: ParamSpec("x", "rad", 0.0, "x", bounds=(1, 1)), "low < high"),
        (lambda: ParamSpec("x", "rad", 0.0, "x", bounds=(0, math.inf)), "finite"),
        (lambda: ParamSpec("x", "rad", 0.0, "x", bounds=(0, 1, 2)), "finite"),  # type: ignore[arg-type]
        (lambda: ParamSpec("x", "rad", 0.0, "x", tunable=True), "tunable parameter needs bounds"),
        (lambda: ParamSpec("x", "rad", 0.0, "x", joint_poses=True), "joint_poses needs a list"),
        (lambda: GaitSpec("g", "g", GENTLE.params * 2, _gentle), "distinct parameter names"),
        (
            lambda: GaitSpec("g", "g", GENTLE.params, _gentle, ties=(("amplitude", "omegaa"),)),
            "unknown parameter 'omegaa'",
        ),
        (
            lambda: GaitSpec("g", "g", GENTLE.params, _gentle, ties=(("amplitude",),)),
            "two or more",
        ),
        (
            lambda: GaitSpec(
                "g",
                "g",
                (GENTLE.params[0], ParamSpec("omega", "rad/s", 1.0, "untuned", bounds=(0, 1))),
                _gentle,
                ties=(("amplitude", "omega"),),
            ),
            "all tunable or none",
        ),
    ],
)
def test_specs_that_do_not_fit_together_are_refused(make: Callable[[], object], match: str) -> None:
    with pytest.raises(GaitError, match=match):
        make()


def test_default_search_takes_tunable_parameters_in_order_with_ties_joined() -> None:
    params = (
        ParamSpec("b", "rad", 0.0, "b", bounds=(0, 1), tunable=True),
        ParamSpec("a", "rad", 0.0, "a", bounds=(0, 1)),
        ParamSpec("c", "rad", 0.0, "c", bounds=(0, 1), tunable=True),
        ParamSpec("d", "rad", 0.0, "d", bounds=(0, 1), tunable=True),
    )
    spec = GaitSpec("g", "g", params, _gentle, ties=(("d", "b"),))
    assert spec.default_search == ("d+b", "c")


class _Follower(Gait):
    """Holds the measured pose: a closed-loop gait that declares nothing."""

    joint_count = 3

    def targets(self, time_s: object) -> FloatArray:
        return np.zeros(3)

    def command(self, time_s: float, measured_rad: FloatArray | None = None) -> FloatArray:
        return np.zeros(3) if measured_rad is None else measured_rad.copy()


def test_gaits_declare_whether_they_use_the_measured_pose() -> None:
    assert not make_gait("serpenoid", 4).uses_measured_pose
    assert not make_gait("keyframes", 4).uses_measured_pose
    assert make_gait("keyframes", 4, {"advance": "error"}).uses_measured_pose
    assert _Follower().uses_measured_pose  # overriding command() counts as using it
