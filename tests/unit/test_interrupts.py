"""The stop-signal recorder: raised at safe points only, nested holders, handlers put back."""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Iterator

import pytest

from snakebot import interrupts
from snakebot.interrupts import deferred_interrupts

pytestmark = pytest.mark.skipif(os.name != "posix", reason="signals to self need POSIX")


@pytest.fixture(autouse=True)
def handlers_as_they_were() -> Iterator[None]:
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
    yield
    for signum, handler in before.items():
        signal.signal(signum, handler)


def test_a_recorded_signal_raises_at_the_next_safe_point_once_per_signal() -> None:
    held = deferred_interrupts()
    held.arm()
    os.kill(os.getpid(), signal.SIGINT)
    os.kill(os.getpid(), signal.SIGINT)
    assert held.count == 2  # nothing raised between the kills and here
    with pytest.raises(KeyboardInterrupt):
        held.deliver()
    assert held.count == 1
    with pytest.raises(KeyboardInterrupt):  # the second Ctrl-C: the next safe point again
        held.deliver()
    held.deliver()  # nothing waiting
    with held:  # a stop: no signal waiting, nothing raised after it
        pass
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_two_holders_share_one_recorder_and_the_last_out_puts_the_handlers_back() -> None:
    first, second = deferred_interrupts(), deferred_interrupts()
    first.arm()
    second.arm()
    os.kill(os.getpid(), signal.SIGINT)
    assert first.count == second.count == 1
    with pytest.raises(KeyboardInterrupt), first:  # closed first: takes the signal waiting
        pass
    assert second.count == 0
    assert signal.getsignal(signal.SIGINT) is not signal.default_int_handler  # second still holds
    os.kill(os.getpid(), signal.SIGINT)
    with pytest.raises(KeyboardInterrupt), second:
        pass
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_ignored_and_default_signals_stay_as_they_are() -> None:
    signal.signal(signal.SIGHUP, signal.SIG_IGN)  # nohup
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    with deferred_interrupts() as held:
        assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
        os.kill(os.getpid(), signal.SIGHUP)
        assert held.count == 0
    assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN


def test_a_holder_in_another_thread_changes_nothing() -> None:
    seen = []

    def connect_in_a_thread() -> None:
        held = deferred_interrupts()
        held.arm()
        seen.append(signal.getsignal(signal.SIGINT))
        with held:
            pass

    thread = threading.Thread(target=connect_in_a_thread)
    thread.start()
    thread.join()
    assert seen == [signal.default_int_handler]


def test_a_flag_setting_handler_gets_its_signal_at_the_safe_point_and_nothing_raises() -> None:
    flags: list[int] = []

    def flag(signum: int, frame: object) -> None:
        flags.append(signum)

    signal.signal(signal.SIGTERM, flag)
    held = deferred_interrupts()
    held.arm()
    os.kill(os.getpid(), signal.SIGTERM)
    assert flags == []
    held.deliver()
    assert flags == [signal.SIGTERM]
    with held:
        pass
    assert signal.getsignal(signal.SIGTERM) is flag


class Clock:
    def __init__(self) -> None:
        self.now_s = 0.0

    def monotonic(self) -> float:
        return self.now_s


def test_a_loop_that_stopped_asking_still_gets_a_later_ctrl_c_but_a_stop_never(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    clock = Clock()
    monkeypatch.setattr(interrupts, "time", clock)
    held = deferred_interrupts()
    held.arm()
    os.kill(os.getpid(), signal.SIGINT)  # waits for a safe point that does not come
    clock.now_s = interrupts.UNANSWERED_S - 0.1
    os.kill(os.getpid(), signal.SIGINT)
    assert held.count == 2
    clock.now_s = interrupts.UNANSWERED_S
    with pytest.raises(KeyboardInterrupt):
        os.kill(os.getpid(), signal.SIGINT)  # the third, 2 s on: raised where the loop is
        signal.pthread_kill(threading.get_ident(), 0)  # (a call: the handler runs by here)
    with pytest.raises(KeyboardInterrupt), held as stop:  # the stop still counts all it gets
        clock.now_s += 10 * interrupts.UNANSWERED_S
        os.kill(os.getpid(), signal.SIGINT)
        assert stop.count == 3
