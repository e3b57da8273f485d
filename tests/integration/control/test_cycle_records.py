"""What a run's observers see every cycle, open-ended runs ended by a stop check, and the slew
limit on a cycle that ran late (real dynamixel_sdk over the in-process emulator, virtual time)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from snakebot.backends.chain import ServoChainBackend
from snakebot.backends.twin import TwinBackend
from snakebot.config import RobotConfig, load_robot
from snakebot.control.cycle import CycleRecord
from snakebot.control.metrics import RunMetrics
from snakebot.control.runner import RunPlan, run_gait
from snakebot.control.safety import SafetyLayer, smooth_ramp
from snakebot.emulation import make_chain_for_ids, registered
from snakebot.emulation.port import EmulatedPortHandler
from snakebot.gaits import make_gait


def metrics_for(robot: RobotConfig) -> RunMetrics:
    return RunMetrics(robot.joint_count, robot.body_length_m, robot.total_mass_kg)


def test_every_cycle_is_recorded_with_its_command_state_error_and_timing() -> None:
    robot = load_robot("snake8")  # ramp_s 1.0
    records: list[CycleRecord] = []
    safety = SafetyLayer.for_robot(robot)
    with TwinBackend(robot) as twin:
        result = run_gait(
            twin,
            make_gait("serpenoid", 8),
            safety,
            RunPlan(2.0),
            metrics_for(robot),
            observers=[records.append],
        )
    scored = [r for r in records if r.scored]
    assert len(scored) == result.summary["control_cycles"] == 200
    assert [r.cycle for r in records] == list(range(1, len(records) + 1))
    assert all(not r.scored for r in records[200:]) and len(records) > 290  # the ramp-out
    assert np.array_equal(records[-1].command_rad, safety.rest_rad)
    assert [r.amplitude for r in scored[:2]] == [0.0, smooth_ramp(0.01 / safety.ramp_s)]
    errors = np.array([r.tracking_error_rad for r in scored])
    rms = float(np.sqrt(np.mean(errors**2)))
    assert rms == pytest.approx(result.summary["tracking_rms_rad"], rel=1e-12)
    assert all(abs(r.period_s - 0.01) < 1e-12 for r in records)
    assert not any(r.overrun for r in records)
    assert abs(records[-1].achieved_rate_hz - 100.0) < 1e-6
    assert records[-1].time_s == records[-1].state.time_s == twin.data.time


def test_an_open_ended_run_goes_on_until_its_stop_check_says_why() -> None:
    robot = load_robot("snake8")
    seen: list[CycleRecord] = []

    def enough() -> str | None:
        return "far enough" if len(seen) >= 120 else None

    with TwinBackend(robot) as twin:
        result = run_gait(
            twin,
            make_gait("serpenoid", 8),
            SafetyLayer.for_robot(robot),
            RunPlan(None),
            metrics_for(robot),
            observers=[seen.append],
            stop=enough,
        )
    assert result.stopped_by == "far enough" and not result.interrupted
    assert result.summary["control_cycles"] == 120
    assert result.summary["duration_s"] == 1.2
    assert not seen[-1].scored and np.abs(seen[-1].command_rad).max() == 0.0  # ramped out


def test_a_late_cycle_is_flagged_and_the_next_step_gets_the_time_that_passed() -> None:
    """The host stalls 15 ms after cycle 40 (descheduled on a loaded machine): cycle 41 is late,
    and the command after it may move the joints as far as they could in the time it took."""
    base = load_robot("snake12")
    robot = dataclasses.replace(base, safety=dataclasses.replace(base.safety, ramp_s=0.0))
    chain = make_chain_for_ids(robot.servo.name, robot.servo_ids, baud=robot.bus.baud)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    records: list[CycleRecord] = []

    def stall(cycle: int, gait_time_s: float) -> None:
        if cycle == 40:
            chain.advance(0.015)

    fast = make_gait("serpenoid", 12, {"omega": 12.0, "amplitude": 1.4})  # slew-limited
    with registered(chain) as url:
        backend = ServoChainBackend(
            robot,
            port=url,
            port_handler_factory=EmulatedPortHandler,
            clock=lambda: chain.now_s,
            sleep=chain.advance,
        )
        with backend:
            run_gait(
                backend,
                fast,
                SafetyLayer.for_robot(robot),
                RunPlan(1.0),
                metrics_for(robot),
                on_cycle=stall,
                observers=[records.append],
            )
    late = records[40]  # cycle 41
    assert late.overrun and late.period_s > 0.015
    assert [r.cycle for r in records if r.overrun] == [41]
    assert late.achieved_rate_hz < records[39].achieved_rate_hz
    steps = np.abs(np.diff([r.command_rad for r in records], axis=0)).max(axis=1)
    budget = robot.max_speed_rad_s * 0.01
    on_time = np.delete(steps, 40)  # every other step: one period's worth at most
    assert on_time.max() <= budget * (1 + 1e-6) and on_time.max() > 0.99 * budget
    # records[41] was commanded after the late cycle: it may go as far as the time allowed.
    assert budget * 1.4 < steps[40] <= robot.max_speed_rad_s * min(late.period_s, 0.02) + 1e-12
