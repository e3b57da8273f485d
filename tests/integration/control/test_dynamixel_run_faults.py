"""Each bus fault during a full run: the documented behaviour, the log kept, the servos left safe.

Real dynamixel_sdk over the in-process emulator on its virtual clock; faults are injected through
the chain at cycle 30 of a 100 Hz sidewinding run on snake12.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest

from snakebot.backends.chain import ServoChainBackend
from snakebot.config import RobotConfig, load_robot
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, RunResult, run_gait
from snakebot.control.safety import SafetyLayer
from snakebot.emulation import EmulatedChain, HardwareError, make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.errors import BusError, ServoFaultError
from snakebot.gaits import make_gait
from snakebot.telemetry import CsvTelemetryWriter, read_log

FAULT_CYCLE = 30
Fault = Callable[[EmulatedChain], None]


@pytest.fixture
def chain() -> Iterator[tuple[EmulatedChain, str]]:
    robot = load_robot("snake12")
    chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud=robot.bus.baud)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    with registered(chain) as url:
        yield chain, url


def run_with_fault(
    chain: EmulatedChain, url: str, fault: Fault, log_path: Path, policy: str = "hold"
) -> RunResult:
    base = load_robot("snake12")
    robot: RobotConfig = dataclasses.replace(
        base, safety=dataclasses.replace(base.safety, ramp_s=0.3, stop_policy=policy)
    )
    backend = ServoChainBackend(
        robot,
        port=url,
        port_handler_factory=EmulatedPortHandler,
        clock=lambda: chain.now_s,
        sleep=chain.advance,
    )
    metrics = RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)

    def inject(cycle: int, gait_time_s: float) -> None:
        if cycle == FAULT_CYCLE:
            fault(chain)

    with CsvTelemetryWriter(log_path, robot.joint_count) as log, backend:
        return run_gait(
            backend,
            make_gait("sidewinding", 12),
            SafetyLayer.for_robot(robot),
            RunPlan(duration_s=1.0),
            metrics,
            log=log,
            on_cycle=inject,
        )


def assert_log_intact(log_path: Path, at_least: int) -> None:
    data = read_log(log_path)
    assert data.values.shape[0] >= at_least
    np.testing.assert_array_equal(data.column("cycle"), np.arange(data.values.shape[0]))
    assert np.isfinite(data.joints("position_rad")).all()


def assert_left_safe(chain: EmulatedChain, servo_ids: range, policy: str = "hold") -> None:
    for servo_id in servo_ids:
        servo = chain.servo(servo_id)
        assert servo.torque_enabled == (policy == "hold"), servo_id
        if policy == "hold":
            assert abs(servo.peek("goal_position") - 2048) <= 2, servo_id  # the straight pose


@pytest.mark.parametrize(
    "fault",
    [
        pytest.param(lambda c: c.drop_replies(5, next_n=1), id="dropped-reply"),
        pytest.param(lambda c: c.corrupt_replies(7, next_n=1), id="corrupt-reply"),
        pytest.param(lambda c: c.delay_replies(3, 0.005), id="late-reply"),
    ],
)
def test_transient_faults_are_retried_and_the_run_completes(
    chain: tuple[EmulatedChain, str], fault: Fault, tmp_path: Path
) -> None:
    emulated, url = chain
    result = run_with_fault(emulated, url, fault, tmp_path / "run.csv")
    assert not result.interrupted
    assert result.summary["duration_s"] == pytest.approx(1.0, abs=0.02)  # the whole gait ran
    cycles = int(result.summary["control_cycles"])  # type: ignore[call-overload]
    assert cycles >= 90  # a retry costs a few cycles' worth of bus time, no more
    assert_log_intact(tmp_path / "run.csv", cycles)
    assert_left_safe(emulated, range(1, 13))


@pytest.mark.parametrize(
    "fault",
    [
        pytest.param(lambda c: c.silence(4), id="silent-servo"),
        pytest.param(lambda c: c.delay_replies(4, 0.2), id="reply-past-timeout"),
        pytest.param(lambda c: c.servo(4).poke("baud_rate", 1), id="wrong-baud"),
    ],
)
def test_a_lost_servo_stops_the_run_naming_it(
    chain: tuple[EmulatedChain, str], fault: Fault, tmp_path: Path
) -> None:
    emulated, url = chain
    with pytest.raises(BusError) as info:
        run_with_fault(emulated, url, fault, tmp_path / "run.csv")
    assert 4 in info.value.servo_ids
    assert "4" in str(info.value)
    assert_log_intact(tmp_path / "run.csv", FAULT_CYCLE)
    assert_left_safe(emulated, range(1, 4))
    assert_left_safe(emulated, range(5, 13))


@pytest.mark.parametrize("policy", ["hold", "limp"])
def test_a_latched_hardware_error_stops_the_run_naming_servo_and_bit(
    chain: tuple[EmulatedChain, str], policy: str, tmp_path: Path
) -> None:
    emulated, url = chain
    fault: Fault = lambda c: c.latch_hardware_error(9, HardwareError.OVERLOAD)  # noqa: E731
    with pytest.raises(ServoFaultError) as info:
        run_with_fault(emulated, url, fault, tmp_path / "run.csv", policy)
    assert info.value.servo_id == 9
    assert any("overload" in flag.lower() for flag in info.value.flags)
    assert "servo reboot" in str(info.value) and "--id 9" in str(info.value)
    assert_log_intact(tmp_path / "run.csv", FAULT_CYCLE)
    healthy = [i for i in range(1, 13) if i != 9]
    for servo_id in healthy:
        assert emulated.servo(servo_id).torque_enabled == (policy == "hold")
    assert not emulated.servo(9).torque_enabled  # the firmware cut its torque
