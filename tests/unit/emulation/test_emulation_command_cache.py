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


@pytest.mark.parametrize(("model", "order"), [("STS3215", "little"), ("SCS0009", "big")])
def test_a_feetech_servos_cached_command_equals_a_fresh_decode(model: str, order: str) -> None:
    from snakebot.emulation import firmware_feetech

    rng = random.Random(4)
    servo = VirtualServo(model, 1)
    count = servo.table.specs.ticks.count
    for _ in range(300):
        choice = rng.random()
        if choice < 0.1:  # angle limits, sometimes both 0 (multi-turn / motor mode)
            low = 0 if rng.random() < 0.3 else rng.randint(0, count // 2)
            high = 0 if low == 0 and rng.random() < 0.5 else rng.randint(count // 2, count - 1)
            servo.write(9, low.to_bytes(2, order) + high.to_bytes(2, order))
        elif choice < 0.2 and servo.memory.has("homing_offset"):
            magnitude = rng.randint(0, 2047)
            raw = magnitude | (1 << 11 if rng.random() < 0.5 else 0)
            servo.write(31, raw.to_bytes(2, order))
        elif choice < 0.3:
            servo.write(40, bytes([rng.choice((0, 1))]))
        else:
            servo.write(42, rng.randint(0, count - 1).to_bytes(2, order))
        assert servo.command() == firmware_feetech.command(servo)
        servo.step(0.001)
