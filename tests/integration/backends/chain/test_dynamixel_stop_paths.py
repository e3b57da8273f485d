"""Every way out of the backend ends in the stop policy once any servo may have torque on.

A failed connect, Ctrl-C anywhere in connect, Ctrl-C (once, twice) or any other exception during
the stop ramp: the servos that still answer end as ``stop_policy`` says (hold: torque on, Bus
Watchdog disarmed; limp: torque off), and nobody's watchdog trips afterwards.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.emulation import EmulatedChain, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.errors import BusError
from snakebot.types import JointCommand
from tests.integration.backends.chain.conftest import (
    BAUD,
    Bench,
    ChainWatcher,
    make_bench,
    robot_variant,
)

BENT = np.linspace(-0.8, 0.8, 12)


def assert_left_per_policy(chain: EmulatedChain, policy: str, skip: tuple[int, ...] = ()) -> None:
    """Torque as the policy says on every answering servo, watchdog disarmed, and no trip later."""
    servos = [s for s in chain.servos if s.servo_id not in skip]
    for servo in servos:
        assert servo.torque_enabled == (policy == "hold"), servo.servo_id
        assert servo.peek("bus_watchdog") == 0, servo.servo_id
    chain.advance(1.0)  # nobody feeds the bus now
    for servo in servos:
        assert not servo.watchdog_tripped, servo.servo_id
        assert servo.torque_enabled == (policy == "hold"), servo.servo_id


def silence_when_torque_on(servo_id: int) -> Callable[[EmulatedChain], None]:
    def watch(chain: EmulatedChain) -> None:
        servo = chain.servo(servo_id)
        if servo.torque_enabled and not chain.faults_of(servo).silent:
            chain.silence(servo_id)

    return watch


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_a_servo_lost_right_after_torque_on_fails_connect_with_the_policy_applied(
    bench: Bench, policy: str
) -> None:
    bench.chain.physics = ChainWatcher(bench.chain, silence_when_torque_on(7))
    backend = bench.backend(robot_variant(ramp_s=0.2, stop_policy=policy))
    with pytest.raises(BusError) as info:
        backend.connect()
    assert 7 in info.value.servo_ids
    assert not backend.bus.is_open
    assert_left_per_policy(bench.chain, policy, skip=(7,))


class Interrupt:
    """Raise KeyboardInterrupt the ``at``-th time bus time passes, as a Ctrl-C mid-transaction."""

    def __init__(self, at: int) -> None:
        self.at = at
        self.count = 0

    def __call__(self, chain: EmulatedChain) -> None:
        self.count += 1
        if self.count == self.at:
            raise KeyboardInterrupt


def connect_calls() -> int:
    """How many times bus time passes in one whole connect (the places a Ctrl-C can land)."""
    chain = make_bench(range(1, 13))
    with registered(chain) as url:
        counter = Interrupt(at=-1)
        chain.physics = ChainWatcher(chain, counter)
        backend = Bench(chain, url).backend()
        backend.connect()
        count = counter.count
        backend.close()  # a connected backend holds the stop signals back until it closes
    return count


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_ctrl_c_anywhere_in_connect_leaves_the_servos_per_policy(policy: str) -> None:
    total = connect_calls()
    assert total > 50
    robot = robot_variant(ramp_s=0.2, stop_policy=policy)
    for at in range(1, total + 1, max(1, total // 40)):
        chain = make_bench(range(1, 13))
        with registered(chain) as url:
            chain.physics = ChainWatcher(chain, Interrupt(at))
            backend = Bench(chain, url).backend(robot)
            with pytest.raises(KeyboardInterrupt):
                backend.connect()
            assert not backend.bus.is_open, at
            chain.physics = None
            on = [s.torque_enabled for s in chain.servos]
            if policy == "limp" or not any(on):
                assert not any(on), at
            else:
                assert all(on), at
            assert {s.peek("bus_watchdog") for s in chain.servos} == {0}, at
            chain.advance(1.0)
            assert not any(s.watchdog_tripped for s in chain.servos), at


def ramp_backend(bench: Bench, policy: str, on_sleep: Callable[[int], None]) -> ServoChainBackend:
    """A backend whose k-th sleep (from 1) first calls ``on_sleep(k)`` (a signal arriving then)."""
    chain = bench.chain
    count = 0

    def sleep(dt: float) -> None:
        nonlocal count
        count += 1
        on_sleep(count)
        chain.advance(dt)

    return ServoChainBackend(
        robot_variant(ramp_s=1.0, stop_policy=policy),
        port=bench.url,
        baud=BAUD,
        port_handler_factory=EmulatedPortHandler,
        clock=lambda: chain.now_s,
        sleep=sleep,
    )


def bend(backend: ServoChainBackend) -> None:
    for _ in range(150):
        backend.send_command(JointCommand(BENT))
        backend.advance(0.01)


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_ctrl_c_during_the_stop_ramp_finishes_it_faster_then_applies_the_policy(
    bench: Bench, policy: str
) -> None:
    sleeps: list[int] = []
    trigger = {"at": None}

    def on_sleep(k: int) -> None:
        sleeps.append(k)
        if trigger["at"] is not None and k == trigger["at"]:
            raise KeyboardInterrupt

    backend = ramp_backend(bench, policy, on_sleep)
    backend.connect()
    bend(backend)
    trigger["at"] = len(sleeps) + 10  # 0.1 s into the 1 s ramp
    start_s = bench.chain.now_s
    with pytest.raises(KeyboardInterrupt):
        backend.close()
    took_s = bench.chain.now_s - start_s
    assert took_s < 0.6  # hurried: the rest at the joint speed limit, not the full second
    if policy == "hold":
        assert {s.peek("goal_position") for s in bench.chain.servos} == {2048}  # still got there
    assert_left_per_policy(bench.chain, policy)


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_a_second_ctrl_c_during_the_stop_ramp_still_ends_in_the_policy(
    bench: Bench, policy: str
) -> None:
    sleeps: list[int] = []
    triggers: set[int] = set()

    def on_sleep(k: int) -> None:
        sleeps.append(k)
        if k in triggers:
            raise KeyboardInterrupt

    backend = ramp_backend(bench, policy, on_sleep)
    backend.connect()
    bend(backend)
    triggers.update({len(sleeps) + 10, len(sleeps) + 12})
    with pytest.raises(KeyboardInterrupt):
        backend.close()
    assert not backend.bus.is_open
    assert_left_per_policy(bench.chain, policy)


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_any_exception_in_the_stop_ramp_still_ends_in_the_policy(bench: Bench, policy: str) -> None:
    sleeps: list[int] = []
    fail = {"at": None}

    def on_sleep(k: int) -> None:
        sleeps.append(k)
        if k == fail["at"]:
            raise RuntimeError("clock failed")

    backend = ramp_backend(bench, policy, on_sleep)
    backend.connect()
    bend(backend)
    fail["at"] = len(sleeps) + 5
    with pytest.raises(RuntimeError, match="clock failed"):
        backend.close()
    assert not backend.bus.is_open
    assert_left_per_policy(bench.chain, policy)


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_ctrl_c_propagating_into_close_ramps_at_the_speed_limit(bench: Bench, policy: str) -> None:
    backend = ramp_backend(bench, policy, lambda k: None)
    with pytest.raises(KeyboardInterrupt), backend:
        bend(backend)
        start_s = bench.chain.now_s
        raise KeyboardInterrupt  # a second Ctrl-C, after the runner's own ramp-out began
    took_s = bench.chain.now_s - start_s
    # 0.8 rad at the speed limit (0.9 x no-load) on a cosine profile: ~0.25 s, not ramp_s = 1 s
    assert 0.1 < took_s < 0.5
    if policy == "hold":
        assert {s.peek("goal_position") for s in bench.chain.servos} == {2048}
    assert_left_per_policy(bench.chain, policy)
