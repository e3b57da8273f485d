"""Fixtures: emulated chains behind ``dxlemu://`` URLs, and the CLI run in-process on them.

Everything goes through the real dynamixel_sdk: the setup tools open the URL with the emulator's
port handler, on the chain's virtual clock (a missing reply costs no real 34 ms).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import pytest

from snakebot.cli.main import main
from snakebot.emulation.bench import ServoBench, robot_servos
from snakebot.emulation.chain import EmulatedChain
from snakebot.emulation.registry import registered
from snakebot.emulation.virtual_servo import VirtualServo

MODEL = "XL430-W250"
ROBOT_BAUD = 1_000_000


@dataclass
class Bus:
    """A registered emulated chain: its URL and the servos on it."""

    chain: EmulatedChain
    url: str

    def servo(self, servo_id: int) -> VirtualServo:
        return self.chain.servo(servo_id)

    def eeprom(self) -> list[bytes]:
        """Every servo's EEPROM bytes, in chain order."""
        return [bytes(s.memory.data[:64]) for s in self.chain.servos]


@dataclass
class Cli:
    """``snakebot`` in-process: exit code and captured output."""

    capsys: pytest.CaptureFixture[str]

    def __call__(self, *argv: str) -> tuple[int, str, str]:
        self.capsys.readouterr()
        code = main(list(argv))
        captured = self.capsys.readouterr()
        return code, captured.out, captured.err


@pytest.fixture
def cli(capsys: pytest.CaptureFixture[str]) -> Cli:
    return Cli(capsys)


def snake12_chain(baud: int = ROBOT_BAUD) -> EmulatedChain:
    """snake12's twelve servos with factory settings at IDs 1..12 (what `emulate` starts with)."""
    return EmulatedChain(robot_servos(MODEL, range(1, 13), baud), baud=baud)


@pytest.fixture
def snake() -> Iterator[Bus]:
    chain = snake12_chain()
    with registered(chain) as url:
        yield Bus(chain, url)


@pytest.fixture
def fresh() -> Iterator[tuple[Bus, ServoBench]]:
    """An empty bus with twelve factory-fresh servos waiting to be plugged in."""
    chain = EmulatedChain(baud=57600)
    bench = ServoBench(chain, MODEL, fresh=12)
    with registered(chain) as url:
        yield Bus(chain, url), bench
