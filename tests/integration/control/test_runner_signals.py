"""A stop signal during a run reaches the loop between cycles: every observer (the CSV log, the
MCAP file, Foxglove) sees the same cycles, the interrupted one included (the twin, in-process).

CI once caught the MCAP file one joint state short of the CSV log after a SIGTERM: the signal's
KeyboardInterrupt had landed between the two sinks of one cycle.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator

import pytest

from snakebot.backends.twin import TwinBackend
from snakebot.config import load_robot
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.gaits import make_gait


@pytest.fixture
def raising_stop_handlers() -> Iterator[None]:
    """SIGINT and SIGTERM raise KeyboardInterrupt, as under the CLI."""

    def interrupt(signum: int, frame: object) -> None:
        raise KeyboardInterrupt

    previous = {sig: signal.signal(sig, interrupt) for sig in (signal.SIGINT, signal.SIGTERM)}
    yield
    for sig, handler in previous.items():
        signal.signal(sig, handler)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
@pytest.mark.usefixtures("raising_stop_handlers")
def test_a_signal_inside_one_observer_reaches_the_loop_after_every_observer_saw_the_cycle(
    sig: signal.Signals,
) -> None:
    robot = load_robot("snake8")
    first: list[CycleRecord] = []
    second: list[CycleRecord] = []

    def signalling(record: CycleRecord) -> None:
        first.append(record)
        if record.cycle == 50:
            os.kill(os.getpid(), sig)  # its handler runs here, before this observer returns
            for _ in range(100):  # ... at the latest by a few bytecodes later
                pass

    with TwinBackend(robot) as twin:
        result = run_gait(
            twin,
            make_gait("serpenoid", 8),
            SafetyLayer.for_robot(robot),
            RunPlan(5.0),
            RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg),
            observers=[signalling, second.append],
        )
    assert result.interrupted
    assert result.summary["control_cycles"] == 50  # the gait ended after the cycle it came in
    assert [r.cycle for r in first] == [r.cycle for r in second]
    assert len(first) > 50 and not any(r.scored for r in first[50:])  # then the ramp-out
