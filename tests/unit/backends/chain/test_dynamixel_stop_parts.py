"""Pure pieces of the stop and supervision paths: tracking check, catch-up, trip count, ramps,
deferred interrupts."""

from __future__ import annotations

import math
import os
import signal

import numpy as np
import pytest

from snakebot.backends.chain.shutdown import fastest_ramp_s, ramp_duration_s, ramp_poses
from snakebot.backends.chain.supervision import (
    CatchUp,
    TrackingLimits,
    TrackingMonitor,
    TripCounter,
)
from snakebot.interrupts import deferred_interrupts

RAD_PER_TICK = 2 * math.pi / 4096


def test_a_joint_standing_still_while_its_goal_sweeps_is_flagged_after_the_window() -> None:
    monitor = TrackingMonitor(TrackingLimits(), 2, RAD_PER_TICK)
    flagged = []
    for k in range(30):  # every 0.1 s: joint 0 follows a sweep, joint 1 stays at 2048
        t = 0.1 * k
        goal = 2048 + round(400 * math.sin(t * math.pi))
        flagged += [(round(t, 1), s.joint) for s in monitor.check(t, [goal, 2048], [goal, goal])]
    assert flagged and {j for _, j in flagged} == {1}
    assert flagged[0][0] >= 1.0  # not before the 1 s window


def test_a_lagging_joint_that_still_moves_is_not_flagged() -> None:
    monitor = TrackingMonitor(TrackingLimits(), 1, RAD_PER_TICK)
    for k in range(50):
        t = 0.1 * k
        goal = 2048 + round(600 * math.sin(t * math.pi))
        present = 2048 + round(300 * math.sin(t * math.pi - 1.0))  # half the swing, late
        assert monitor.check(t, [present], [goal]) == []


def test_catch_up_slews_to_the_commands_then_stops_limiting() -> None:
    catch = CatchUp([2000, 2048], max_ticks_per_s=1000.0, now_s=0.0)
    assert catch.limit([2100, 2048], 0.01) == [2010, 2048] and not catch.done
    goals = [catch.limit([2100, 2048], 0.01 * k) for k in range(2, 12)]
    assert goals[-1] == [2100, 2048] and catch.done


def test_trips_are_counted_within_the_window() -> None:
    trips = TripCounter(10.0)
    assert [trips.add(t) for t in (0.0, 4.0, 9.0, 15.0)] == [1, 2, 3, 2]
    assert trips.total == 4


def test_tracking_limits_are_checked() -> None:
    with pytest.raises(ValueError, match="window_s"):
        TrackingLimits(window_s=0.0)


def test_the_stop_ramp_never_beats_the_speed_limit() -> None:
    assert ramp_duration_s(0.1, 5.0, 1.0) == 1.0
    assert ramp_duration_s(2.0, 5.0, 0.3) == pytest.approx(math.pi / 5.0)
    poses = ramp_poses(np.array([2.0]), np.array([0.0]), fastest_ramp_s(2.0, 5.0), rate_hz=1000)
    times = np.array([0.0] + [t for t, _ in poses])
    angles = np.array([2.0] + [p[0] for _, p in poses])
    assert np.max(np.abs(np.diff(angles) / np.diff(times))) <= 5.0 + 1e-6


@pytest.mark.skipif(os.name != "posix", reason="signals to self")
def test_a_signal_during_the_final_writes_is_raised_after_them() -> None:
    done = []
    with pytest.raises(KeyboardInterrupt), deferred_interrupts() as signals:
        os.kill(os.getpid(), signal.SIGINT)
        done.append("still running")  # the block is not cut short
    assert done == ["still running"] and signals.caught == [signal.SIGINT]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.mark.skipif(os.name != "posix", reason="signals to self")
def test_deferred_signals_are_counted_and_go_to_the_handler_they_were_meant_for() -> None:
    def terminate(signum: int, frame: object) -> None:
        raise SystemExit(f"terminated by {signum}")

    previous = {s: signal.signal(s, terminate) for s in (signal.SIGTERM, signal.SIGHUP)}
    try:
        first = f"terminated by {int(signal.SIGHUP)}"
        with pytest.raises(SystemExit, match=first), deferred_interrupts() as signals:
            for signum in (signal.SIGHUP, signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
                os.kill(os.getpid(), signum)
            assert signals.caught == [signal.SIGHUP, signal.SIGTERM, signal.SIGINT, signal.SIGHUP]
        assert signal.getsignal(signal.SIGTERM) is terminate
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def test_a_keyboard_interrupt_noted_inside_is_raised_as_it_was() -> None:
    original = KeyboardInterrupt("by hand")
    with pytest.raises(KeyboardInterrupt) as info, deferred_interrupts() as signals:
        signals.note(original)
        assert signals.count == 1
    assert info.value is original
