"""config apply warns about a servo standing outside the position limits it is about to write."""

from __future__ import annotations

import dataclasses
import warnings

import pytest

from snakebot.setup.apply import PositionOutsideLimitsWarning
from tests.integration.setup.conftest import Bus, Cli


def test_apply_warns_about_a_servo_outside_the_limits_it_writes(snake: Bus, cli: Cli) -> None:
    servo = snake.servo(3)  # factory limits 0..4095; the servo file wants -110..110 deg
    servo.state = dataclasses.replace(servo.state, position_rad=2.5)  # 143 deg
    with pytest.warns(PositionOutsideLimitsWarning) as caught:
        code, _, err = cli("config", "apply", "--robot", "snake12", "--port", snake.url, "--yes")
    assert code == 0, err
    messages = [str(w.message) for w in caught]
    assert len(messages) == 1
    assert messages[0].startswith("servo 3 stands at 2.500 rad from centre")
    assert "outside the Min/Max Position Limit -110.039..110.039 deg" in messages[0]
    assert "Move the joint inside by hand" in messages[0]


def test_apply_is_quiet_when_every_servo_stands_inside(snake: Bus, cli: Cli) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", PositionOutsideLimitsWarning)
        code, _, err = cli("config", "apply", "--robot", "snake12", "--port", snake.url, "--yes")
    assert code == 0, err
