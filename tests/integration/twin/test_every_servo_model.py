"""Every shipped servo file gives the twin a servo that works: a 12-joint snake of that model at
its factory gains sidewinds with the joints following, never faster than the model's no-load
speed, and without the twin's physics warnings."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from snakebot.cli.main import main
from snakebot.config import load_robot
from tests.conftest import CONFIGS

MODELS = sorted(
    line.split('"')[1]
    for path in (CONFIGS / "servos").glob("*.toml")
    for line in path.read_text().splitlines()
    if line.startswith("model = ")
)
# snake12's 85 g modules suit every model but the 540 case (165 g, e-Manual): at 10.6 N·m its
# light modules bounce into the floor, so it gets modules of its own weight; the STS3250 (4.9 N·m
# at its factory P 32) too.
MODULE_MASS_KG = {"XM540-W270": 0.2, "STS3250": 0.15}


@pytest.mark.parametrize("model", MODELS)
def test_a_snake_of_each_model_sidewinds_on_the_twin(
    config_dir: Path, capsys: pytest.CaptureFixture[str], model: str
) -> None:
    text = (config_dir / "robots" / "snake12.toml").read_text()
    gains = text[text.index("[gains]") : text.index("[settings]")]
    path = config_dir / "robots" / "model.toml"
    mass = f"mass_kg = {MODULE_MASS_KG.get(model, 0.085)} "
    path.write_text(
        text.replace('servo = "XL430-W250"', f'servo = "{model}"')
        .replace(gains, "")
        .replace('name = "snake12"', 'name = "model"')
        .replace("mass_kg = 0.085 ", mass)
        .replace("protocol = 2.0\n", "")
    )  # the model's own protocol (AX: 1.0)
    robot = load_robot(path)  # no [gains]: the model's factory gains
    argv = ["run", "--robot", str(path), "--gait", "sidewinding", "--duration", "3", "--json"]
    assert main(argv) == 0
    summary = json.loads(capsys.readouterr().out)
    physics = summary["physics"]
    assert summary["tracking_rms_rad"] < 0.3
    assert physics["max_joint_speed_rad_s"] <= physics["no_load_speed_rad_s"]
    assert physics["warnings"] == []
    assert robot.gains == robot.servo.factory_gains
