"""The emulator's cost per control cycle is linear in the chain, and its physics does not depend
on how a transport cuts time: the stock SDK's Sync Write + Fast Sync Read over dxlemu://."""

from __future__ import annotations

import math
from collections.abc import Callable

import dynamixel_sdk as sdk
import pytest

from snakebot.emulation import EmulatedChain, VirtualServo, make_chain_for_ids, registered
from snakebot.emulation.chain import SETTLE_AFTER_S
from snakebot.emulation.motion import ProfileMotion
from snakebot.emulation.port import EmulatedPortHandler

BAUD = 4_000_000
GOAL, READ, READ_LENGTH = 116, 126, 10


class CountingMotion(ProfileMotion):
    """The stock kinematic model; counts how often the chain steps it."""

    def __init__(self) -> None:
        super().__init__()
        self.steps = 0

    def step(self, servo: VirtualServo, dt_s: float) -> None:
        self.steps += 1
        super().step(servo, dt_s)


def moving_chain(n: int, *, acceleration: int = 0) -> EmulatedChain:
    chain = make_chain_for_ids("XL430-W250", range(1, n + 1), BAUD)
    for servo in chain.servos:
        servo.motion = CountingMotion()
        servo.processing_time_s = 24e-6  # the same reply timing on every chain made
        servo.poke("return_delay_time", 0)
        servo.poke("profile_acceleration", acceleration)
        servo.poke("torque_enable", 1)
    return chain


def run_cycles(
    chain: EmulatedChain, cycles: int, between: Callable[[EmulatedChain], None] | None = None
) -> list[list[int]]:
    """Sync Write of travelling-sine goals + Fast Sync Read, as ServoChainBackend cycles; returns
    Present Position of every servo per cycle."""
    ids = [s.servo_id for s in chain.servos]
    with registered(chain, "cost") as url:
        port = EmulatedPortHandler(url)
        port.setBaudRate(BAUD)
        packet = sdk.PacketHandler(2.0)
        writer = sdk.GroupSyncWrite(port, packet, GOAL, 4)
        reader = sdk.GroupSyncRead(port, packet, READ, READ_LENGTH)
        for servo_id in ids:
            writer.addParam(servo_id, [0, 8, 0, 0])
            reader.addParam(servo_id)
        readings = []
        for k in range(cycles):
            for servo_id in ids:
                ticks = round(2048 + 600 * math.sin(0.3 * k - 0.6 * servo_id))
                writer.changeParam(servo_id, list(ticks.to_bytes(4, "little")))
            assert writer.txPacket() == sdk.COMM_SUCCESS
            assert reader.fastSyncRead() == sdk.COMM_SUCCESS
            readings.append([reader.getData(i, 132, 4) for i in ids])
            if between is not None:
                between(chain)
        port.closePort()
    return readings


def motion_steps(chain: EmulatedChain) -> int:
    return sum(s.motion.steps for s in chain.servos if isinstance(s.motion, CountingMotion))


@pytest.mark.parametrize("n", [8, 32])
def test_each_servo_is_stepped_twice_per_cycle_whatever_the_chain_length(n: int) -> None:
    # Measured before the fix: N + 2 steps per servo per cycle (one per reply segment of the
    # Fast Sync Read), so the emulator's cost grew with N squared. Now: one per packet, plus one
    # per SETTLE_AFTER_S of bus time (a cycle here takes well under 2 ms).
    chain = moving_chain(n)
    run_cycles(chain, 3)
    before, start_s = motion_steps(chain), chain.now_s
    run_cycles(chain, 20)
    per_servo = (motion_steps(chain) - before) / n
    assert per_servo <= 2 * 20 + math.ceil((chain.now_s - start_s) / SETTLE_AFTER_S)


def test_motion_does_not_depend_on_how_the_time_between_cycles_is_cut() -> None:
    # With a profile acceleration the kinematic model integrates; 5 ms between cycles passed in
    # one piece or in 50 pieces must give the same trajectory (to floating rounding).
    one, many = moving_chain(4, acceleration=40), moving_chain(4, acceleration=40)
    got_one = run_cycles(one, 40, lambda c: c.advance(0.005))

    def in_pieces(chain: EmulatedChain) -> None:
        for _ in range(50):
            chain.advance(0.0001)

    got_many = run_cycles(many, 40, in_pieces)
    assert got_one == got_many
    for a, b in zip(one.servos, many.servos, strict=True):
        assert a.state.position_rad == pytest.approx(b.state.position_rad, abs=1e-9)
        assert a.state.velocity_rad_s == pytest.approx(b.state.velocity_rad_s, abs=1e-9)
    assert got_one[-1] != got_one[-2]  # the servos were moving


def test_a_servo_held_from_outside_lags_the_bus_clock_by_less_than_the_settle_period() -> None:
    chain = moving_chain(2)
    servo = chain.servos[0]
    servo.poke("goal_position", 3000)
    chain.advance(0.001)
    start = servo.state.position_rad
    for _ in range(int(2 * SETTLE_AFTER_S / 0.001)):
        chain.advance(0.001)
    moved = servo.state.position_rad - start
    assert moved > 0.0  # stepped by the chain itself, no look-up needed
    chain.settle()
    assert servo.uptime_s == pytest.approx(chain.now_s, abs=1e-9)
