"""close(): ramp from the present pose to the safe pose, then hold or limp per the config."""

from __future__ import annotations

import numpy as np
import pytest

from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.errors import SnakebotError
from snakebot.types import JointCommand
from tests.integration.backends.chain.conftest import BAUD, Bench, robot_variant

BENT = np.linspace(-0.8, 0.8, 12)


def recording_backend(bench: Bench, policy: str, goals: list[int]) -> ServoChainBackend:
    """A backend whose sleeps log servo 12's goal, so the ramp can be inspected afterwards."""
    chain = bench.chain

    def sleep(dt: float) -> None:
        goals.append(chain.servo(12).peek("goal_position"))
        chain.advance(dt)

    return ServoChainBackend(
        robot_variant(ramp_s=0.3, stop_policy=policy),
        port=bench.url,
        baud=BAUD,
        port_handler_factory=EmulatedPortHandler,
        clock=lambda: chain.now_s,
        sleep=sleep,
    )


def bend(backend: ServoChainBackend) -> None:
    backend.send_command(JointCommand(BENT))
    for _ in range(100):
        backend.advance(0.01)
        backend.send_command(JointCommand(BENT))


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_close_ramps_to_the_safe_pose_then_applies_the_policy(bench: Bench, policy: str) -> None:
    goals: list[int] = []
    backend = recording_backend(bench, policy, goals)
    backend.connect()
    bend(backend)
    goals.clear()
    start_s = bench.chain.now_s
    backend.close()
    ramp = np.array(goals)
    assert bench.chain.now_s - start_s == pytest.approx(0.3, abs=0.02)
    assert len(ramp) >= 25  # ~100 Hz goal updates over 0.3 s
    assert ramp[0] > 2500 and ramp[-1] == 2048  # from 0.8 rad (2569) to 0 rad
    assert np.all(np.diff(ramp) <= 0)  # monotonic, no jump back
    assert np.max(np.abs(np.diff(ramp))) < 150  # no single jump (0.8 rad is 521 ticks)
    assert {s.peek("goal_position") for s in bench.chain.servos} == {2048}
    torque = {s.torque_enabled for s in bench.chain.servos}
    assert torque == {policy == "hold"}
    assert backend.torque_enabled == (policy == "hold")
    assert {s.peek("bus_watchdog") for s in bench.chain.servos} == {0}  # disarmed
    assert not backend.bus.is_open
    bench.chain.advance(1.0)  # nobody feeds the bus now: hold must not trip, limp stays limp
    assert not any(s.watchdog_tripped for s in bench.chain.servos)


def test_close_after_an_exception_still_ramps_and_holds(bench: Bench) -> None:
    with pytest.raises(RuntimeError, match="gait crashed"), bench.backend() as backend:
        bend(backend)
        raise RuntimeError("gait crashed")
    assert {s.peek("goal_position") for s in bench.chain.servos} == {2048}
    assert all(s.torque_enabled for s in bench.chain.servos)
    bench.chain.advance(0.5)
    present = [s.peek("present_position") for s in bench.chain.servos]
    assert max(abs(p - 2048) for p in present) <= 1


def test_close_with_torque_off_moves_nothing(bench: Bench) -> None:
    backend = bench.backend(enable_torque=False)
    backend.connect()
    backend.close()
    assert not any(s.torque_enabled for s in bench.chain.servos)


def test_close_survives_a_servo_that_dropped_out(bench: Bench) -> None:
    backend = bench.backend()
    backend.connect()
    bend(backend)
    bench.chain.silence(4)
    with pytest.raises(SnakebotError):
        backend.read_state()
    backend.close()
    others = [s for s in bench.chain.servos if s.servo_id != 4]
    assert {s.peek("goal_position") for s in others} == {2048}
    assert not backend.bus.is_open
