"""A tripped Bus Watchdog and joints that stop following their goals are noticed, not ignored.

Real dynamixel_sdk over the in-process emulator on its virtual clock; snake12 runs sidewinding at
100 Hz. A trip the host cannot see is made the way a starved emulator (or a USB stall the host's
clock does not show) makes it: bus time passes that the backend's clock does not count.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable, Iterator

import numpy as np
import pytest

from snakebot.backends.chain import ServoChainBackend
from snakebot.backends.chain.faults import TrackingError, WatchdogTripError
from snakebot.config import RobotConfig, load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, RunResult, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.emulation import EmulatedChain, ExternalMotion, make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.gaits import make_gait
from snakebot.types import JointCommand

Hook = Callable[[int, EmulatedChain, "SkewedClock"], None]


class SkewedClock:
    """The host's clock: the bus clock minus time the host never saw pass."""

    def __init__(self, chain: EmulatedChain) -> None:
        self.chain = chain
        self.unseen_s = 0.0

    def __call__(self) -> float:
        return self.chain.now_s - self.unseen_s

    def stall_unseen(self, seconds: float) -> None:
        """Bus time passes (the servos' watchdogs count it) that the host does not notice."""
        self.chain.advance(seconds)
        self.unseen_s += seconds


@pytest.fixture
def chain() -> Iterator[tuple[EmulatedChain, str]]:
    robot = load_robot("snake12")
    chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud=robot.bus.baud)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    with registered(chain) as url:
        yield chain, url


def robot(policy: str = "hold") -> RobotConfig:
    base = load_robot("snake12")
    return dataclasses.replace(
        base, safety=dataclasses.replace(base.safety, ramp_s=0.3, stop_policy=policy)
    )


def run(
    chain: EmulatedChain,
    url: str,
    hook: Hook,
    *,
    duration_s: float = 2.0,
    policy: str = "hold",
    presents: list[np.ndarray] | None = None,
) -> RunResult:
    clock = SkewedClock(chain)
    config = robot(policy)
    backend = ServoChainBackend(
        config, port=url, port_handler_factory=EmulatedPortHandler, clock=clock, sleep=chain.advance
    )

    def on_cycle(cycle: int, gait_time_s: float) -> None:
        hook(cycle, chain, clock)
        if presents is not None:
            presents.append(np.array([s.peek("present_position") for s in chain.servos]))

    with backend:
        return run_gait(
            backend,
            make_gait("sidewinding", 12),
            SafetyLayer.for_robot(config),
            RunPlan(duration_s=duration_s),
            RunMetrics(12, config.body_length_m, config.total_mass_kg),
            on_cycle=on_cycle,
        )


def assert_straight_and_holding(chain: EmulatedChain) -> None:
    for servo in chain.servos:
        assert servo.torque_enabled, servo.servo_id
        assert servo.peek("goal_position") == 2048, servo.servo_id  # the safe pose was taken
        assert servo.peek("bus_watchdog") == 0, servo.servo_id
    chain.advance(1.0)
    assert not any(s.watchdog_tripped for s in chain.servos)
    assert max(abs(s.peek("present_position") - 2048) for s in chain.servos) <= 2


def longest_freeze_s(presents: list[np.ndarray], dt_s: float = 0.01) -> float:
    """Longest time every joint's reading stayed exactly the same, in s."""
    longest = run_length = 0
    for before, after in itertools.pairwise(presents):
        run_length = run_length + 1 if np.array_equal(before, after) else 0
        longest = max(longest, run_length)
    return longest * dt_s


def test_a_watchdog_trip_the_host_did_not_see_is_recovered(
    chain: tuple[EmulatedChain, str],
) -> None:
    emulated, url = chain

    def hook(cycle: int, bus: EmulatedChain, clock: SkewedClock) -> None:
        if cycle == 30:
            clock.stall_unseen(0.15)  # longer than the 100 ms watchdog
            assert all(s.watchdog_tripped for s in bus.servos)

    presents: list[np.ndarray] = []
    result = run(emulated, url, hook, presents=presents)
    assert longest_freeze_s(presents) <= 0.25  # noticed within two slow-rate periods
    assert_straight_and_holding(emulated)
    assert result.summary["backend_stats"]["watchdog_trips"] == 1  # type: ignore[index]


def test_a_trip_just_before_the_end_does_not_leave_a_bent_pose(
    chain: tuple[EmulatedChain, str],
) -> None:
    emulated, url = chain

    def hook(cycle: int, bus: EmulatedChain, clock: SkewedClock) -> None:
        if cycle == 95:  # in the last 50 ms of a 1 s gait: no slow read before the ramp-out
            clock.stall_unseen(0.15)

    run(emulated, url, hook, duration_s=1.0)
    assert_straight_and_holding(emulated)


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_trips_that_keep_coming_stop_the_run_with_a_typed_error(
    chain: tuple[EmulatedChain, str], policy: str
) -> None:
    emulated, url = chain

    def hook(cycle: int, bus: EmulatedChain, clock: SkewedClock) -> None:
        if cycle % 25 == 0:
            clock.stall_unseen(0.15)

    with pytest.raises(WatchdogTripError) as info:
        run(emulated, url, hook, duration_s=5.0, policy=policy)
    assert info.value.trips == 4
    assert "tripped 4 times within 10 s" in str(info.value)
    for servo in emulated.servos:
        assert servo.torque_enabled == (policy == "hold")
        assert servo.peek("bus_watchdog") == 0
        if policy == "hold":
            assert servo.peek("goal_position") == 2048


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_a_jammed_joint_stops_the_run_naming_it(
    chain: tuple[EmulatedChain, str], policy: str
) -> None:
    emulated, url = chain

    def hook(cycle: int, bus: EmulatedChain, clock: SkewedClock) -> None:
        if cycle == 60:
            bus.servo(5).motion = ExternalMotion()  # the shaft stops dead: torque on, no fault

    presents: list[np.ndarray] = []
    with pytest.raises(TrackingError) as info:
        run(emulated, url, hook, duration_s=5.0, policy=policy, presents=presents)
    error = info.value
    assert (error.joints, error.servo_ids) == ((4,), (5,))
    assert "joint 4 (servo 5)" in str(error) and "blocked or jammed" in str(error)
    assert len(presents) < 60 + 160  # noticed within 1.6 s, not at the end of the 5 s run
    for servo in emulated.servos:
        assert servo.torque_enabled == (policy == "hold")
        assert servo.peek("bus_watchdog") == 0


def test_a_servo_that_rebooted_mid_run_is_named(chain: tuple[EmulatedChain, str]) -> None:
    emulated, url = chain

    def hook(cycle: int, bus: EmulatedChain, clock: SkewedClock) -> None:
        if cycle == 60:
            bus.servo(8).reboot()  # a supply dip: torque off, RAM back to defaults

    with pytest.raises(TrackingError) as info:
        run(emulated, url, hook, duration_s=5.0)
    assert 8 in info.value.servo_ids
    assert "Torque Enable reads 0 on servo(s) 8" in str(info.value)


def test_a_trip_during_the_stop_ramp_is_cleared_and_the_ramp_done_again(
    chain: tuple[EmulatedChain, str],
) -> None:
    emulated, url = chain
    clock = SkewedClock(emulated)
    config = robot()
    sleeps = {"n": 0, "stall_at": -1}

    def sleep(dt: float) -> None:
        sleeps["n"] += 1
        if sleeps["n"] == sleeps["stall_at"]:
            clock.stall_unseen(0.15)
        emulated.advance(dt)

    backend = ServoChainBackend(
        config, port=url, port_handler_factory=EmulatedPortHandler, clock=clock, sleep=sleep
    )
    with backend:
        for _ in range(100):
            backend.send_command(JointCommand(np.full(12, 0.6)))
            backend.advance(0.01)
        sleeps["stall_at"] = sleeps["n"] + 10  # a third into the 0.3 s stop ramp
    assert_straight_and_holding(emulated)
