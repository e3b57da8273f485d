"""`snakebot gaits`: where each gait comes from, and per parameter unit, default, bounds, tuned."""

from __future__ import annotations

import json
from collections.abc import Iterator

import pytest

from snakebot.cli.main import main
from snakebot.gaits import GAITS, GaitSpec, get_spec, register_gait


@pytest.fixture
def gentle() -> Iterator[None]:
    serpenoid = get_spec("serpenoid")
    register_gait(GaitSpec("gentle_wave", "a script's gait", serpenoid.params, serpenoid.factory))
    yield
    GAITS.unregister("gentle_wave")


def test_text_listing_shows_origin_bounds_and_the_default_search(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["gaits", "serpenoid"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("serpenoid [built-in]: Hirose serpenoid")
    rows = {line.split()[0]: line.split() for line in lines[2:6]}
    assert rows["omega"][:5] == ["omega", "rad/s", "pi", "0.5:6*pi", "yes"]
    assert rows["offset"][:5] == ["offset", "rad", "0", "-0.3:0.3", "-"]
    assert lines[6].strip() == "tune gait searches by default: omega, phase_lag"


def test_json_listing_carries_origin_bounds_and_tunable(
    gentle: None, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["gaits", "--json"]) == 0
    listing = {g["name"]: g for g in json.loads(capsys.readouterr().out)}
    assert listing["gentle_wave"]["origin"] == "registered at runtime"
    keyframes = listing["keyframes"]
    assert keyframes["origin"] == "built-in" and keyframes["distribution"] is None
    poses = keyframes["params"][0]
    assert (
        poses["joint_poses"]
        and poses["tunable"]
        and poses["bounds"] == pytest.approx([-0.7853981633974483, 0.7853981633974483])
    )
    assert listing["sidewinding"]["default_search"][2] == "spatial_freq_even+spatial_freq_odd"
    assert listing["rolling"]["rolls_over"] and listing["rolling"]["default_search"] == []


def test_an_unknown_gait_is_an_error_with_a_hint(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["gaits", "serpentine"]) == 2
    assert "did you mean 'serpenoid'" in capsys.readouterr().err
