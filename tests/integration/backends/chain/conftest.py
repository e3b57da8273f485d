"""The real dynamixel_sdk over the in-process emulator (``dxlemu://``, virtual time).

The backend's clock and sleep are the emulated bus clock: ``advance(dt)`` lets dt of bus time pass,
so the servos' motion and watchdogs run exactly as far as the test says, in microseconds of CPU.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import pytest

from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.config import load_robot
from snakebot.config.schema import RobotConfig
from snakebot.emulation import EmulatedChain, VirtualServo, make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler

BAUD = 1_000_000
MODEL = "XL430-W250"


def robot_variant(name: str = "snake12", **safety: Any) -> RobotConfig:
    """A loaded robot with some safety fields replaced (ramp_s, stop_policy)."""
    robot = load_robot(name)
    return dataclasses.replace(robot, safety=dataclasses.replace(robot.safety, **safety))


@dataclass
class Bench:
    """An emulated chain registered under ``url`` and a way to build backends on it."""

    chain: EmulatedChain
    url: str

    def servo(self, servo_id: int) -> VirtualServo:
        return self.chain.servo(servo_id)

    def backend(self, robot: RobotConfig | None = None, **kwargs: Any) -> ServoChainBackend:
        chain = self.chain
        return ServoChainBackend(
            robot or robot_variant(ramp_s=0.2),
            port=self.url,
            baud=BAUD,
            port_handler_factory=EmulatedPortHandler,
            clock=lambda: chain.now_s,
            sleep=chain.advance,
            **kwargs,
        )

    def add(self, servo_id: int, model: str = MODEL) -> VirtualServo:
        return self.chain.add(VirtualServo(model, servo_id, baud=BAUD))


def make_bench(ids: range | list[int], return_delay: int = 0) -> EmulatedChain:
    chain = make_chain_for_ids(MODEL, ids, baud=BAUD)
    for servo in chain.servos:
        servo.poke("return_delay_time", return_delay)
    return chain


@pytest.fixture
def bench() -> Iterator[Bench]:
    """Twelve XL430-W250 with IDs 1..12 at 1 Mbps, Return Delay Time 0 (snake12's chain)."""
    chain = make_bench(range(1, 13))
    with registered(chain) as url:
        yield Bench(chain, url)


class ChainWatcher:
    """A ``ChainPhysics`` that moves nothing: it calls ``callback(chain)`` whenever bus time passes.

    The emulator calls its physics hook from inside every transaction (wire time, reply waits), so
    a callback can inject a fault at the exact moment the bus reaches a state, e.g. one servo going
    silent right after its torque comes on, or a Ctrl-C arriving mid-transaction.
    """

    def __init__(self, chain: EmulatedChain, callback: Any) -> None:
        self.chain = chain
        self.callback = callback
        self.calls = 0

    def advance(self, servos: Any, dt_s: float) -> None:
        self.calls += 1
        self.callback(self.chain)
