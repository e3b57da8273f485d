"""``--terrain`` and ``--friction-model`` on the command line."""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import pytest

from snakebot.cli.main import main


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["--terrain", "pegs:density=5000"], ("density", "0.01..2000 1/m^2", "5000")),
        (["--terrain", "slope:tilt=5"], ("tilt", "angle_deg (0..45 deg)", "direction_deg")),
        (["--terrain", "lava"], ("lava", "flat, slope, pegs, rough, step, pipe, pole, cliff")),
        (["--terrain", "pipe:inner_diameter_m=0.03"], ("inner_diameter_m", "link radii")),
        (
            ["--friction-model", "scale", "--backend", "dynamixel", "--robot", "snake8"],
            ("--friction-model does nothing with the dynamixel backend",),
        ),
        (["--friction-model", "scale", "--robot", "worm"], ("rigid twin only",)),
    ],
)
def test_bad_terrain_options_are_usage_errors_naming_the_key(
    argv: list[str], words: tuple[str, ...], capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["run", "--duration", "0.2", *argv]) == 2
    err = capsys.readouterr().err
    assert "error:" in err and "Traceback" not in err
    for word in words:
        assert word in err


def test_run_on_a_terrain_with_the_scale_model(capsys: pytest.CaptureFixture[str]) -> None:
    argv = [
        "run", "--robot", "snake8", "--terrain", "rough:roughness_m=0", "--friction",
        "0.05,0.5,1.0", "--duration", "3", "--json",
    ]  # fmt: skip
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["distance_m"] > 0.3  # lateral undulation works on the height field


def test_model_exports_the_terrain(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "pipe.xml"
    assert main(["model", "--robot", "snake8", "--terrain", "pipe", "--out", str(out)]) == 0
    model = mujoco.MjModel.from_xml_path(str(out))
    assert model.geom("pipe0").size[2] == pytest.approx(0.005)
    assert model.npair == 0 and model.sensor("snakebot_contact_load").dim[0] == 9  # links
