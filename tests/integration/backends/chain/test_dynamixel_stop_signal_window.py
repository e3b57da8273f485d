"""No stop signal, at any Python event between the runner's Ctrl-C and the stop, skips the stop.

A run of the real runner (``run_gait``) on a Dynamixel backend over the real SDK and the emulator
gets a Ctrl-C (a real SIGINT to this process) during its gait. Then, at the k-th Python event (a
call or a line, under ``sys.settrace``) of the way out (the runner's exit path, the context
manager's ``__exit__``, ``close``, ``_close``, the stop sequence up to its first transaction),
one or two more real SIGINTs arrive, for every k. Whatever k, the servos must end as the stop
policy says: Torque Enable per policy, Bus Watchdog 0, goals inside the joint limits.
"""

from __future__ import annotations

import os
import signal
import sys
import typing
from types import FrameType
from typing import Any

import pytest

from snakebot import interrupts
from snakebot.backends.base import Backend
from snakebot.backends.chain.backend import ServoChainBackend
from snakebot.backends.chain.stopping import StopSequence
from snakebot.control import runner
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.emulation import registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.gaits import make_gait
from snakebot.types import JointCommand, StopPolicy
from tests.integration.backends.chain.conftest import BAUD, make_bench, robot_variant
from tests.integration.backends.chain.test_dynamixel_stop_paths import assert_left_per_policy
from tests.integration.backends.chain.test_dynamixel_stop_signals import (
    assert_goals_inside_limits,
)

pytestmark = pytest.mark.skipif(os.name != "posix", reason="signals to self need POSIX")

POLICIES = typing.get_args(StopPolicy)
WAY_OUT = {  # the runner's exit path and the backend's, to the stop's first transaction
    f"{code.co_filename}:{code.co_name}"
    for code in (
        runner.run_gait.__code__,
        runner._ramp_out.__code__,
        Backend.__exit__.__code__,
        Backend.close.__code__,
        ServoChainBackend._close.__code__,
        StopSequence.close.__code__,
        interrupts.deferred_interrupts.__code__,
        interrupts.DeferredInterrupts.__init__.__code__,
        interrupts.DeferredInterrupts.__enter__.__code__,
        interrupts.DeferredInterrupts.arm.__code__,
    )
}
FIRST_CTRL_C_CYCLE = 5


def _name(frame: FrameType) -> str:
    return f"{frame.f_code.co_filename}:{frame.f_code.co_name}"


class WayOut:
    """A trace function: counts the events of the way out from the first Ctrl-C to the stop's
    first transaction (``StopSequence._stop`` is entered) and sends ``signals`` SIGINTs at the
    ``fire_at``-th."""

    def __init__(self, fire_at: int | None = None, signals: int = 0) -> None:
        self.fire_at, self.signals = fire_at, signals
        self.events = 0
        self.done = False

    def __call__(self, frame: FrameType, event: str, arg: Any) -> Any:
        if self.done:
            return None
        if frame.f_code is StopSequence._stop.__code__:
            self.done = True
            return None
        if _name(frame) not in WAY_OUT:
            return None
        self.events += 1
        if self.events == self.fire_at:
            self.done = True
            for _ in range(self.signals):
                os.kill(os.getpid(), signal.SIGINT)
        return self

    def start(self) -> None:
        """Trace from here: new frames, and the runner's frames already running."""
        frame = sys._getframe(1)
        while frame is not None:
            if _name(frame) in WAY_OUT:
                frame.f_trace = self
            frame = frame.f_back  # type: ignore[assignment]
        sys.settrace(self)


def ctrl_c_run(policy: str, way_out: WayOut) -> None:
    """snake12 sidewinding under the runner until a Ctrl-C at cycle 5, then the way out."""
    chain = make_bench(range(1, 13))
    robot = robot_variant(ramp_s=0.03, stop_policy=policy)
    with registered(chain) as url:
        backend = ServoChainBackend(
            robot,
            port=url,
            baud=BAUD,
            port_handler_factory=EmulatedPortHandler,
            clock=lambda: chain.now_s,
            sleep=chain.advance,
        )

        def on_cycle(cycle: int, gait_time_s: float) -> None:
            if cycle == FIRST_CTRL_C_CYCLE:
                way_out.start()
                os.kill(os.getpid(), signal.SIGINT)

        try:
            with backend:  # the extra SIGINTs may raise after the stop, or join the first one
                run_gait(
                    backend,
                    make_gait("sidewinding", 12),
                    SafetyLayer.for_robot(robot),
                    RunPlan(duration_s=5.0),
                    RunMetrics(12, robot.body_length_m, robot.total_mass_kg),
                    on_cycle=on_cycle,
                )
        except KeyboardInterrupt:
            pass
        finally:
            sys.settrace(None)
        assert not backend.bus.is_open
        assert_goals_inside_limits(chain, backend)
        assert_left_per_policy(chain, policy)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.mark.parametrize("policy", POLICIES)
def test_a_ctrl_c_at_any_event_of_the_way_out_still_ends_in_the_stop_policy(policy: str) -> None:
    dry = WayOut()
    ctrl_c_run(policy, dry)
    assert dry.done and dry.events >= 20, dry.events  # the way out was traced to the stop
    for signals in (1, 2):
        for k in range(1, dry.events + 1):
            way_out = WayOut(k, signals)
            try:
                ctrl_c_run(policy, way_out)
            except AssertionError as exc:
                raise AssertionError(f"{signals} SIGINT(s) at event {k} of {dry.events}") from exc
            assert way_out.done, (signals, k)


@pytest.mark.parametrize("policy", POLICIES)
def test_a_users_own_loop_gets_its_ctrl_c_from_the_next_backend_call(policy: str) -> None:
    chain = make_bench(range(1, 13))
    robot = robot_variant(ramp_s=0.1, stop_policy=policy)
    ran_on: list[int] = []
    with registered(chain) as url:
        backend = ServoChainBackend(
            robot,
            port=url,
            baud=BAUD,
            port_handler_factory=EmulatedPortHandler,
            clock=lambda: chain.now_s,
            sleep=chain.advance,
        )
        with pytest.raises(KeyboardInterrupt) as info, backend:
            state = backend.read_state()
            for cycle in range(100):
                backend.send_command(JointCommand(state.position_rad + 0.02 * cycle))
                backend.advance(0.01)
                state = backend.read_state()
                if cycle == 10:
                    os.kill(os.getpid(), signal.SIGINT)
                ran_on.append(cycle)  # the loop's own code is not cut where the signal lands
        assert ran_on == list(range(11))
        raised_in = [entry.name for entry in info.traceback][-4:]  # by the next call
        assert raised_in == ["send_command", "_safe_point", "deliver", "deliver_to"]
        assert_left_per_policy(chain, policy)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
