"""Any error while the bus still works ramps out before it is raised; a bus error does not wait.

Real dynamixel_sdk over the in-process emulator on its virtual clock; snake12 at 100 Hz with a
0.5 s ramp. The telemetry log shows what the servos were told after the error.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest

from snakebot.backends.chain import ServoChainBackend
from snakebot.config import RobotConfig, load_robot
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import CycleHook, RunPlan, RunResult, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.emulation import EmulatedChain, make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.errors import BusError, SafetyLimitError
from snakebot.gaits import Gait, make_gait
from snakebot.telemetry import CsvTelemetryWriter, read_log

FAIL_AT_S = 0.8


class FailingGait(Gait):
    """Sidewinding until ``FAIL_AT_S``, then ``fail(t)`` (raise, or return garbage)."""

    def __init__(self, how: str) -> None:
        self.inner = make_gait("sidewinding", 12)
        self.joint_count = 12
        self.how = how

    def targets(self, time_s: float | npt.ArrayLike) -> npt.NDArray[np.float64]:
        if float(np.max(time_s)) >= FAIL_AT_S:
            if self.how == "raise":
                raise RuntimeError("gait blew up")
            return np.full(12, np.nan)
        return self.inner.targets(time_s)


@pytest.fixture
def chain() -> Iterator[tuple[EmulatedChain, str]]:
    robot = load_robot("snake12")
    chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud=robot.bus.baud)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    with registered(chain) as url:
        yield chain, url


def snake12() -> RobotConfig:
    base = load_robot("snake12")
    return dataclasses.replace(base, safety=dataclasses.replace(base.safety, ramp_s=0.5))


def run(
    chain: EmulatedChain, url: str, gait: Gait, log_path: Path, on_cycle: CycleHook | None = None
) -> RunResult:
    robot = snake12()
    backend = ServoChainBackend(
        robot,
        port=url,
        port_handler_factory=EmulatedPortHandler,
        clock=lambda: chain.now_s,
        sleep=chain.advance,
    )
    metrics = RunMetrics(12, robot.body_length_m, robot.total_mass_kg)
    with CsvTelemetryWriter(log_path, 12) as log, backend:
        return run_gait(
            backend,
            gait,
            SafetyLayer.for_robot(robot),
            RunPlan(duration_s=3.0),
            metrics,
            log=log,
            on_cycle=on_cycle,
        )


def assert_ramped_out_after(log_path: Path, fail_s: float) -> None:
    """The log goes on after the failure for the ramp's 0.5 s, smoothly down to the rest pose."""
    data = read_log(log_path)
    commands = data.joints("command_rad")
    after = data.column("time_s") >= data.column("time_s")[0] + fail_s
    assert 45 <= int(after.sum()) <= 60  # the 0.5 s ramp at 100 Hz
    ramp = np.abs(commands[after]).max(axis=1)
    assert np.all(np.diff(ramp) <= 1e-9)  # falling all the way
    np.testing.assert_array_equal(commands[-1], np.zeros(12))  # ends on the rest pose
    assert np.abs(np.diff(commands, axis=0)).max() < 0.06  # never faster than the slew limit


def test_a_gait_that_raises_ramps_out_then_the_error_is_raised(
    chain: tuple[EmulatedChain, str], tmp_path: Path
) -> None:
    emulated, url = chain
    with pytest.raises(RuntimeError, match="gait blew up"):
        run(emulated, url, FailingGait("raise"), tmp_path / "run.csv")
    assert_ramped_out_after(tmp_path / "run.csv", FAIL_AT_S)
    assert {s.peek("goal_position") for s in emulated.servos} == {2048}


def test_a_gait_returning_nan_ramps_out_then_the_safety_error_is_raised(
    chain: tuple[EmulatedChain, str], tmp_path: Path
) -> None:
    emulated, url = chain
    with pytest.raises(SafetyLimitError, match="non-finite"):
        run(emulated, url, FailingGait("nan"), tmp_path / "run.csv")
    assert_ramped_out_after(tmp_path / "run.csv", FAIL_AT_S)


def test_a_failing_per_cycle_hook_ramps_out_and_is_left_out_of_it(
    chain: tuple[EmulatedChain, str], tmp_path: Path
) -> None:
    emulated, url = chain
    calls: list[int] = []

    def hook(cycle: int, gait_time_s: float) -> None:
        calls.append(cycle)
        if cycle == 80:
            raise OSError("video encoder gone")

    with pytest.raises(OSError, match="video encoder gone"):
        run(emulated, url, make_gait("sidewinding", 12), tmp_path / "run.csv", hook)
    assert calls[-1] == 80  # not called again during the ramp-out
    assert_ramped_out_after(tmp_path / "run.csv", 0.8)


def test_a_failing_observer_alone_is_left_out_of_the_ramp_out(
    chain: tuple[EmulatedChain, str], tmp_path: Path
) -> None:
    emulated, url = chain
    robot = snake12()
    failing_saw: list[int] = []
    other_saw: list[CycleRecord] = []

    def failing(record: CycleRecord) -> None:
        failing_saw.append(record.cycle)
        if record.cycle == 80:
            raise OSError("Foxglove client gone mad")

    backend = ServoChainBackend(
        robot,
        port=url,
        port_handler_factory=EmulatedPortHandler,
        clock=lambda: emulated.now_s,
        sleep=emulated.advance,
    )
    log_path = tmp_path / "run.csv"
    with CsvTelemetryWriter(log_path, 12) as log, backend, pytest.raises(OSError, match="mad"):
        run_gait(
            backend,
            make_gait("sidewinding", 12),
            SafetyLayer.for_robot(robot),
            RunPlan(duration_s=3.0),
            RunMetrics(12, robot.body_length_m, robot.total_mass_kg),
            log=log,
            observers=[failing, other_saw.append],
        )
    assert failing_saw[-1] == 80  # not called again
    assert_ramped_out_after(log_path, 0.8)  # the log before it went on
    # the observer after it missed only the cycle it stopped, and went on through the ramp-out
    cycles = [r.cycle for r in other_saw]
    assert cycles == [c for c in range(1, len(read_log(log_path).values) + 1) if c != 80]
    assert other_saw[78].scored and not other_saw[-1].scored


def test_a_bus_error_is_raised_at_once_for_the_backend_to_stop(
    chain: tuple[EmulatedChain, str], tmp_path: Path
) -> None:
    emulated, url = chain

    def hook(cycle: int, gait_time_s: float) -> None:
        if cycle == 80:
            emulated.silence(4)

    with pytest.raises(BusError):
        run(emulated, url, make_gait("sidewinding", 12), tmp_path / "run.csv", hook)
    data = read_log(tmp_path / "run.csv")
    assert data.values.shape[0] == 80  # no ramp-out rows: the bus is not trusted
    others = [s for s in emulated.servos if s.servo_id != 4]
    assert {s.peek("goal_position") for s in others} == {2048}  # the backend's stop ramp


def test_a_ramp_out_on_a_late_host_still_ends_on_the_rest_pose(
    chain: tuple[EmulatedChain, str], tmp_path: Path
) -> None:
    emulated, url = chain
    stalling = {"on": False}

    def hook(cycle: int, gait_time_s: float) -> None:
        if cycle == 150:
            stalling["on"] = True  # from here every cycle comes 60 ms late (a loaded host)
        if stalling["on"]:
            emulated.advance(0.06)

    robot = snake12()
    backend = ServoChainBackend(
        robot,
        port=url,
        port_handler_factory=EmulatedPortHandler,
        clock=lambda: emulated.now_s,
        sleep=emulated.advance,
    )
    log_path = tmp_path / "run.csv"
    with CsvTelemetryWriter(log_path, 12) as log, backend:
        result = run_gait(
            backend,
            make_gait("sidewinding", 12),
            SafetyLayer.for_robot(robot),
            RunPlan(duration_s=1.6),
            RunMetrics(12, robot.body_length_m, robot.total_mass_kg),
            log=log,
            on_cycle=hook,
        )
    assert result.summary["overruns"] > 5
    commands = read_log(log_path).joints("command_rad")
    np.testing.assert_array_equal(commands[-1], np.zeros(12))
