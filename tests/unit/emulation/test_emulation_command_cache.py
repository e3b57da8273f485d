"""A servo's cached motor command follows Goal Position writes exactly as a fresh decode does."""

import random

import pytest

from snakebot.emulation import VirtualServo, firmware

GOAL = 116


@pytest.mark.parametrize("model", ["XL430-W250", "XM430-W350", "2XL430-W250"])
def test_the_cached_command_equals_a_fresh_decode_after_every_write(model: str) -> None:
    rng = random.Random(3)
    servo = VirtualServo(model, 1)
    for _ in range(300):
        choice = rng.random()
        if choice < 0.1:
            servo.write(64, bytes([0]))
            servo.write(10, bytes([rng.choice((0, 1))]))  # Drive Mode: reverse or not
        elif choice < 0.2:
            servo.write(64, bytes([0]))
            servo.write(20, rng.randint(-1500, 1500).to_bytes(4, "little", signed=True))
        elif choice < 0.3:
            servo.write(64, bytes([1]))
        else:
            servo.write(GOAL, rng.randint(0, 4095).to_bytes(4, "little"))
        assert servo.command() == firmware.command(servo)
        servo.step(0.001)
