"""The control cycle: goals tracked, the tick convention on the wire, torque on, the watchdog."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from snakebot.backends.chain.faults import PoseOutsideLimitsError
from snakebot.config.loader import load_servo_model
from snakebot.config.schema import GainRegisters, RobotConfig
from snakebot.emulation import ExternalMotion, make_chain_for_ids, registered
from snakebot.servo import X_SERIES_TICKS, rad_to_ticks
from snakebot.types import JointCommand, PDGains
from tests.integration.backends.chain.conftest import BAUD, Bench, robot_variant

DT = 0.01


def calibrated_robot() -> RobotConfig:
    robot = robot_variant(ramp_s=0.2)
    joints = tuple(
        dataclasses.replace(j, zero_offset_rad=0.05 * (k - 6), direction=1 if k % 3 else -1)
        for k, j in enumerate(robot.joints)
    )
    return dataclasses.replace(robot, joints=joints)


def wave(t: float) -> np.ndarray:
    return 0.6 * np.sin(2 * math.pi * 0.5 * t - 0.5 * np.arange(12))


def test_a_gait_is_tracked_and_goals_follow_the_tick_convention(bench: Bench) -> None:
    robot = calibrated_robot()
    errors = []
    with bench.backend(robot) as backend:
        for k in range(200):
            goal = wave(k * DT)
            backend.send_command(JointCommand(goal))
            backend.advance(DT)
            errors.append(backend.read_state().position_rad - goal)
        for joint, servo_id in enumerate(robot.servo_ids):
            j = robot.joints[joint]
            expected = rad_to_ticks(
                goal[joint],
                zero_offset_rad=j.zero_offset_rad,
                direction=j.direction,
                ticks=X_SERIES_TICKS,
            )
            assert bench.servo(servo_id).peek("goal_position") == expected
        for _ in range(50):
            backend.advance(DT)
        final = backend.read_state()
    lag = np.sqrt(np.mean(np.square(errors[50:])))
    assert lag < 0.1  # the kinematic servo follows within a few cycles
    np.testing.assert_allclose(final.position_rad, goal, atol=2 * 2 * math.pi / 4096)
    assert backend.stats.overruns == 0


def test_velocity_and_effort_come_back_in_si_with_the_joint_sign(bench: Bench) -> None:
    robot = calibrated_robot()
    with bench.backend(robot) as backend:
        backend.send_command(JointCommand(np.full(12, 0.8)))
        backend.advance(0.05)
        state = backend.read_state()
        assert np.all(state.velocity_rad_s > 0.5)  # moving towards +0.8 in every joint frame
        servo = bench.servo(1)
        servo.motion = ExternalMotion()  # the test, not the kinematic model, sets the load
        servo.state = dataclasses.replace(servo.state, effort=0.5)  # half the stall torque
        effort = backend.read_state().effort_nm[0]
    stall = robot.servo.physics.stall_torque_nm  # supply = nominal voltage in the servo file
    assert effort == pytest.approx(robot.joints[0].direction * 0.5 * stall, rel=0.01)


def test_torque_on_sets_goal_to_present_first(bench: Bench) -> None:
    angles = np.linspace(-0.9, 0.9, 12)
    for servo_id, angle in zip(range(1, 13), angles, strict=True):
        servo = bench.servo(servo_id)
        servo.state = dataclasses.replace(servo.state, position_rad=float(angle))
        servo.poke("goal_position", 2048)  # a stale goal the servo would jump to
    with bench.backend() as backend:
        assert all(s.torque_enabled for s in bench.chain.servos)
        for servo in bench.chain.servos:
            assert servo.peek("goal_position") == servo.peek("present_position")
        backend.advance(0.5)
        np.testing.assert_allclose(backend.read_state().position_rad, angles, atol=1e-3)
        backend.set_torque(False)
        assert not any(s.torque_enabled for s in bench.chain.servos)
        backend.set_torque(True)
        assert all(s.torque_enabled for s in bench.chain.servos)


def test_a_joint_beyond_its_servo_position_limit_is_refused_not_stepped(bench: Bench) -> None:
    servo = bench.servo(3)
    servo.poke("max_position_limit", 3100)  # still covers the joint's 1.5 rad (tick 3025)
    servo.state = dataclasses.replace(servo.state, position_rad=1.7)  # tick 3156: beyond it
    servo.poke("goal_position", 2048)
    backend = bench.backend()
    with pytest.raises(PoseOutsideLimitsError) as info:
        backend.connect()
    error = info.value
    assert (error.joint, error.servo_id) == (2, 3)
    assert error.angle_rad == pytest.approx(1.7, abs=2e-3)
    assert error.limit_rad == pytest.approx((3100 - 2048) * 2 * math.pi / 4096)
    assert "joint 2 (servo 3) measures 1.700 rad" in str(error)
    assert not any(s.torque_enabled for s in bench.chain.servos)  # nothing moved
    bench.chain.advance(0.5)
    assert servo.peek("present_position") == 3156


def test_si_gains_are_written_to_the_position_pid_registers(bench: Bench) -> None:
    with bench.backend() as backend:
        mapping = backend.robot.servo.gain_mapping
        # 900 and 34 register units, a little off so the backend has to round.
        wanted = PDGains(mapping.kp_nm_per_rad(900.3), mapping.kd_nms_per_rad(33.8))
        backend.set_position_i_gain(12)
        backend.set_gains(wanted)
        assert backend.gain_registers == GainRegisters(900, 12, 34)
    got = {
        (s.peek("position_p_gain"), s.peek("position_i_gain"), s.peek("position_d_gain"))
        for s in bench.chain.servos
    }
    assert got == {(900, 12, 34)}


def test_an_mx_on_the_2_0_firmware_gets_its_own_registers_for_the_same_si_gains() -> None:
    # The MX-28 (2.0) has the X map but its own torque and speed: its servo model maps SI gains
    # to its registers; the backend writes what the model says, nothing X-specific.
    mx = load_servo_model("MX-28-2", robot_variant().source)
    robot = dataclasses.replace(robot_variant(ramp_s=0.2), servo=mx)
    chain = make_chain_for_ids("MX-28-2", robot.servo_ids, baud=BAUD)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    wanted = PDGains(kp_nm_per_rad=4.0, kd_nms_per_rad=0.05)
    with registered(chain) as url, Bench(chain, url).backend(robot) as backend:
        backend.set_gains(wanted)
    writes = mx.gain_writes(wanted)
    assert writes["position_p_gain"] == round(4.0 / mx.gain_mapping.kp_nm_per_rad(1)) == 556
    got = {tuple(s.peek(key) for key in writes) for s in chain.servos}
    assert got == {tuple(writes.values())}


def test_gains_beyond_the_registers_are_clipped_to_the_control_table(bench: Bench) -> None:
    with bench.backend() as backend:
        backend.set_gains(PDGains(kp_nm_per_rad=1e6, kd_nms_per_rad=1e6))
        assert backend.gain_registers is not None
        assert (backend.gain_registers.position_p, backend.gain_registers.position_d) == (
            16383,
            16383,
        )
    assert {s.peek("position_p_gain") for s in bench.chain.servos} == {16383}


def test_connect_writes_the_robot_files_registers_back_unchanged(bench: Bench) -> None:
    # snake12's [gains] are registers 640/0/4000: loaded into SI and written back as the same.
    for servo in bench.chain.servos:
        servo.poke("position_p_gain", 100)
        servo.poke("position_d_gain", 7)
    with bench.backend():
        pass
    got = {
        (s.peek("position_p_gain"), s.peek("position_i_gain"), s.peek("position_d_gain"))
        for s in bench.chain.servos
    }
    assert got == {(640, 0, 4000)}


def test_watchdog_is_armed_and_rearmed_after_a_pause(bench: Bench) -> None:
    with bench.backend() as backend:
        assert {s.peek("bus_watchdog") for s in bench.chain.servos} == {5}  # 5 x 20 ms
        bench.chain.advance(0.3)  # the host stalls longer than the watchdog
        assert all(s.watchdog_tripped for s in bench.chain.servos)
        backend.send_command(JointCommand(np.full(12, 0.4)))
        assert not any(s.watchdog_tripped for s in bench.chain.servos)
        for _ in range(100):
            backend.advance(DT)
            backend.send_command(JointCommand(np.full(12, 0.4)))
        np.testing.assert_allclose(backend.read_state().position_rad, 0.4, atol=2e-3)
        assert backend.stats.extra["watchdog_rearms"] == 1


def test_goals_outside_the_joint_limits_are_clipped(bench: Bench) -> None:
    with bench.backend() as backend:
        backend.send_command(JointCommand(np.full(12, 2.5)))
        assert backend.stats.extra["clipped_commands"] == 1
        with pytest.raises(ValueError, match="non-finite"):
            backend.send_command(JointCommand(np.full(12, np.nan)))
    limit = rad_to_ticks(1.5, ticks=X_SERIES_TICKS)
    assert all(s.peek("goal_position") <= limit for s in bench.chain.servos)


def test_slow_rate_reads_report_voltage_and_temperature(bench: Bench) -> None:
    bench.servo(3).state = dataclasses.replace(bench.servo(3).state, temperature_c=55.0)
    with bench.backend() as backend:
        for _ in range(10):
            backend.read_state()
        assert backend.health()["temperature_c"][2] == 55.0
        assert backend.stats.extra["max_temperature_c"] == 55.0
        assert backend.health()["input_voltage_v"] == pytest.approx(np.full(12, 11.1))


def test_xm430_effort_is_current_times_the_torque_constant() -> None:
    robot = robot_variant(ramp_s=0.0)
    robot = dataclasses.replace(robot, servo=load_servo_model("XM430-W350", robot.source))
    chain = make_chain_for_ids("XM430-W350", range(1, 13), baud=BAUD)
    for servo in chain.servos:
        servo.poke("return_delay_time", 0)
    with registered(chain) as url:
        bench = Bench(chain, url)
        servo = bench.servo(2)
        servo.motion = ExternalMotion()
        servo.state = dataclasses.replace(servo.state, current_a=1.0)
        with bench.backend(robot) as backend:
            effort = backend.read_state().effort_nm[1]
    # 1 A in 2.69 mA units, times 4.1 N·m / 2.3 A (e-Manual stall torque and current)
    assert effort == pytest.approx(round(1.0 / 0.00269) * 0.00269 * 4.1 / 2.3, rel=1e-6)


def test_without_current_the_cycle_reads_velocity_and_position_only(bench: Bench) -> None:
    with bench.backend(read_current=False) as backend:
        backend.send_command(JointCommand(np.full(12, 0.3)))
        backend.advance(0.5)
        state = backend.read_state()
        assert backend._state_plan.block.address == 128  # Present Velocity .. Position
    np.testing.assert_allclose(state.position_rad, 0.3, atol=2e-3)
    np.testing.assert_array_equal(state.effort_nm, np.zeros(12))


def test_a_gain_candidates_i_register_reaches_the_servos_beside_the_pd_contract(
    bench: Bench,
) -> None:
    # tune gains searches Position I too: it travels beside the SI gains, Dynamixel only.
    from snakebot.tuning.gains import apply_gains

    with bench.backend() as backend:
        sent = apply_gains(backend, backend.robot, GainRegisters(700, 25, 300))
        assert sent == backend.robot.servo.gains_of(GainRegisters(700, 25, 300))
    got = {
        (s.peek("position_p_gain"), s.peek("position_i_gain"), s.peek("position_d_gain"))
        for s in bench.chain.servos
    }
    assert got == {(700, 25, 300)}
