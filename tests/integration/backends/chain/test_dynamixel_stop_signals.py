"""No number of stop signals, arriving anywhere in the stop path, skips the stop policy.

Real signals (``os.kill`` to this process, so Python's own signal machinery runs) are sent 1, 2,
3 or 5 at a time from inside the bus transactions of ``close`` (the emulator's physics hook runs
inside every one) and from between them (the backend's clock), at points spread over the whole
path, on every stop policy; SIGINT, SIGTERM and SIGHUP take turns. At the end the servos'
registers must read as the policy says: Torque Enable per policy, Bus Watchdog disarmed (0, not
tripped), every goal inside the joint limits, and nothing trips afterwards.
"""

from __future__ import annotations

import os
import signal
import typing
from collections.abc import Iterator
from types import FrameType

import numpy as np
import pytest

from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.emulation import EmulatedChain, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.types import JointCommand, StopPolicy
from tests.integration.backends.chain.conftest import (
    BAUD,
    ChainWatcher,
    make_bench,
    robot_variant,
)
from tests.integration.backends.chain.test_dynamixel_stop_paths import assert_left_per_policy

pytestmark = pytest.mark.skipif(os.name != "posix", reason="signals to self need POSIX")

POLICIES = typing.get_args(StopPolicy)
KINDS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
BENT = np.linspace(-0.8, 0.8, 12)


@pytest.fixture(autouse=True)
def cli_handlers() -> Iterator[None]:
    """SIGTERM and SIGHUP raise KeyboardInterrupt, as ``snakebot``'s entry point makes them."""

    def interrupt(signum: int, frame: FrameType | None) -> None:
        raise KeyboardInterrupt

    previous = {s: signal.signal(s, interrupt) for s in (signal.SIGTERM, signal.SIGHUP)}
    yield
    for signum, handler in previous.items():
        signal.signal(signum, handler)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


class Points:
    """Counts the moments of the stop path (inside transactions, between them) and sends the
    planned signals at the planned ones."""

    def __init__(self, plan: dict[tuple[str, int], list[signal.Signals]] | None = None) -> None:
        self.plan = plan or {}
        self.counts = {"inside": 0, "between": 0}
        self.armed = False
        self.sent = 0

    def at(self, where: str) -> None:
        if not self.armed:
            return
        self.counts[where] += 1
        for signum in self.plan.get((where, self.counts[where]), []):
            self.sent += 1
            os.kill(os.getpid(), signum)


def stopping_backend(
    chain: EmulatedChain, url: str, policy: str, points: Points, ramp_s: float = 0.2
) -> ServoChainBackend:
    """Connected, bent away from the safe pose; every moment of the bus goes to ``points``."""

    def clock() -> float:
        points.at("between")
        return chain.now_s

    backend = ServoChainBackend(
        robot_variant(ramp_s=ramp_s, stop_policy=policy),
        port=url,
        baud=BAUD,
        port_handler_factory=EmulatedPortHandler,
        clock=clock,
        sleep=chain.advance,
    )
    backend.connect()
    for _ in range(20):
        backend.send_command(JointCommand(BENT))
        backend.advance(0.01)
    chain.physics = ChainWatcher(chain, lambda _chain: points.at("inside"))
    return backend


def count_points(policy: str, ramp_s: float = 0.2) -> dict[str, int]:
    chain = make_bench(range(1, 13))
    with registered(chain) as url:
        points = Points()
        backend = stopping_backend(chain, url, policy, points, ramp_s)
        points.armed = True
        backend.close()
    return points.counts


def assert_goals_inside_limits(chain: EmulatedChain, backend: ServoChainBackend) -> None:
    for servo, (_gain, _bias, low, high) in zip(
        chain.servos, backend.converter.goal_terms, strict=True
    ):
        assert low <= servo.peek("goal_position") <= high, servo.servo_id


Plan = dict[tuple[str, int], list[signal.Signals]]


def plans(total: dict[str, int], signals: int) -> Iterator[Plan]:
    """>= 20 moments inside transactions and some between them, spread over the whole path;
    the signals come all at once, or one per moment, or 5 moments apart, in turn."""
    moments = [("inside", k) for k in np.linspace(1, total["inside"], 22).round().astype(int)]
    moments += [("between", k) for k in np.linspace(1, total["between"], 8).round().astype(int)]
    for n, (where, k) in enumerate(moments):
        gap = (0, 1, 5)[n % 3]
        plan: Plan = {}
        for i in range(signals):
            plan.setdefault((where, int(k) + i * gap), []).append(KINDS[(n + i) % len(KINDS)])
        yield plan


@pytest.mark.parametrize("signals", [1, 2, 3, 5])
@pytest.mark.parametrize("policy", POLICIES)
def test_signals_anywhere_in_the_stop_path_still_end_in_the_policy(
    policy: str, signals: int
) -> None:
    total = count_points(policy)
    assert total["inside"] >= 40 and total["between"] >= 10, total
    for plan in plans(total, signals):
        chain = make_bench(range(1, 13))
        with registered(chain) as url:
            points = Points(plan)
            backend = stopping_backend(chain, url, policy, points)
            points.armed = True
            with pytest.raises(KeyboardInterrupt):
                backend.close()
            chain.physics = None
            assert points.sent >= 1, plan  # the first signal landed inside the stop path
            assert not backend.bus.is_open, plan
            assert_goals_inside_limits(chain, backend)
            assert_left_per_policy(chain, policy)


@pytest.mark.parametrize("policy", POLICIES)
def test_a_stop_signal_during_the_ramp_hurries_it_and_the_ramp_still_arrives(policy: str) -> None:
    total = count_points(policy, ramp_s=1.0)
    chain = make_bench(range(1, 13))
    with registered(chain) as url:
        points = Points({("inside", total["inside"] // 4): [signal.SIGHUP]})
        backend = stopping_backend(chain, url, policy, points, ramp_s=1.0)
        points.armed = True
        with pytest.raises(KeyboardInterrupt):
            backend.close()
        chain.physics = None
        assert points.counts["inside"] < 0.6 * total["inside"]  # hurried: the rest at the limit
        assert {s.peek("goal_position") for s in chain.servos} == {2048}  # still got there
        assert_left_per_policy(chain, policy)


def test_the_handler_a_deferred_signal_was_meant_for_gets_it_after_the_policy() -> None:
    # A program of its own with a SIGTERM handler that exits: it gets its SystemExit, after.
    def terminate(signum: int, frame: FrameType | None) -> None:
        raise SystemExit(143)

    previous = signal.signal(signal.SIGTERM, terminate)
    try:
        chain = make_bench(range(1, 13))
        with registered(chain) as url:
            points = Points({("inside", 10): [signal.SIGTERM] * 3})
            backend = stopping_backend(chain, url, "limp", points)
            points.armed = True
            with pytest.raises(SystemExit):
                backend.close()
            chain.physics = None
            assert_left_per_policy(chain, "limp")
    finally:
        signal.signal(signal.SIGTERM, previous)
