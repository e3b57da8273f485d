"""Every shipped robot calibrates on day one: its Position Limits leave room for any offset that
`calibrate` accepts (issue 19: ±100 deg limits left 14 deg where calibrate allows 20)."""

from __future__ import annotations

import math

import pytest

from snakebot.config import load_robot
from snakebot.config.paths import shipped_configs
from snakebot.setup import load_settings
from snakebot.setup.calibrate import MAX_OFFSET_DEG, JointZero, refusals

SHIPPED = sorted(p.stem for p in (shipped_configs() / "robots").glob("*.toml"))


@pytest.mark.parametrize("name", SHIPPED)
@pytest.mark.parametrize("sign", [1, -1])
def test_offsets_up_to_the_calibrate_margin_fit_the_shipped_position_limits(
    name: str, sign: int
) -> None:
    robot = load_robot(name)
    chain = load_settings(robot)
    offset = math.radians(MAX_OFFSET_DEG) * 0.999
    zeros = [
        JointZero(i, j.servo_id, 2048, 0.0, sign * offset * (-1) ** i)
        for i, j in enumerate(robot.joints)
    ]
    assert refusals(chain, zeros) == []


def test_the_shipped_robots_are_the_ones_checked() -> None:
    assert {"snake8", "snake12"} <= set(SHIPPED)
