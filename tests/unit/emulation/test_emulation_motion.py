"""The kinematic motion model and the hook for an external physics model."""

import math
from collections.abc import Sequence

import pytest

from snakebot.emulation import (
    ExternalMotion,
    MotorState,
    ServoCommand,
    VirtualServo,
    make_chain_for_ids,
)

RPM_UNIT = 0.229 * 2 * math.pi / 60  # rad/s per velocity register unit
PULSE = 2 * math.pi / 4096


def write(servo: VirtualServo, key: str, value: int) -> None:
    register = servo.table[key]
    assert servo.write(register.address, register.encode(value)) == 0, key


def run(servo: VirtualServo, seconds: float, dt: float = 0.005) -> list[tuple[int, int]]:
    """(present position, present velocity) every dt."""
    trace = []
    for _ in range(round(seconds / dt)):
        servo.step(dt)
        trace.append((servo.peek("present_position"), servo.peek("present_velocity")))
    return trace


def test_reaches_goal_no_faster_than_the_velocity_limit() -> None:
    servo = VirtualServo("XL430-W250", 1)
    write(servo, "velocity_limit", 100)
    write(servo, "torque_enable", 1)
    write(servo, "goal_position", 3072)
    travel_s = 1024 * PULSE / (100 * RPM_UNIT)
    trace = run(servo, travel_s * 0.9)
    assert trace[-1][0] < 3072
    assert max(abs(v) for _, v in trace) <= 100
    trace = run(servo, travel_s * 0.2)
    assert trace[-1] == (3072, 0) and servo.peek("moving") == 0


def test_profile_velocity_zero_means_no_load_speed() -> None:
    servo = VirtualServo("XL430-W250", 1)
    write(servo, "torque_enable", 1)
    write(servo, "goal_position", 0)
    trace = run(servo, 0.1)
    speed = max(abs(v) for _, v in trace) * RPM_UNIT
    assert speed == pytest.approx(servo.table.specs.no_load_speed_rad_s, rel=0.01)
    assert servo.peek("moving") == 1


def test_profile_velocity_and_acceleration_shape_the_move() -> None:
    servo = VirtualServo("XM430-W350", 1)
    write(servo, "profile_velocity", 50)
    write(servo, "profile_acceleration", 20)
    write(servo, "torque_enable", 1)
    write(servo, "goal_position", 4000)
    trace = run(servo, 0.05)
    accel = 20 * 214.577 * 2 * math.pi / 3600
    assert trace[-1][1] * RPM_UNIT == pytest.approx(accel * 0.05, abs=RPM_UNIT)
    trace = run(servo, 10.0)
    assert max(v for _, v in trace) == 50
    assert trace[-1] == (4000, 0)


def test_velocity_mode_follows_goal_velocity_and_torque_off_stops() -> None:
    servo = VirtualServo("XL430-W250", 1)
    write(servo, "operating_mode", 1)
    write(servo, "torque_enable", 1)
    write(servo, "goal_velocity", -60)
    trace = run(servo, 1.0)
    assert trace[-1][1] == -60
    assert trace[-1][0] == pytest.approx(2048 - 60 * RPM_UNIT / PULSE, abs=2)
    write(servo, "torque_enable", 0)
    assert run(servo, 0.1)[-1][1] == 0


def test_present_current_and_input_voltage_are_reported_in_units() -> None:
    servo = VirtualServo("XM430-W350", 1)
    servo.state = MotorState(
        position_rad=0.0,
        velocity_rad_s=0.0,
        current_a=0.269,
        input_voltage_v=11.1,
        temperature_c=41.4,
    )
    assert servo.peek("present_current") == 100
    assert servo.peek("present_input_voltage") == 111
    assert servo.peek("present_temperature") == 41


class SpringPhysics:
    """A stand-in for the twin: reads the command, writes the state."""

    def __init__(self) -> None:
        self.seen: list[ServoCommand] = []

    def step(self, servo: VirtualServo, dt: float) -> None:
        command = servo.command()
        self.seen.append(command)
        position = servo.state.position_rad
        if command.torque_enabled:
            position += 0.5 * (command.goal_position_rad - position)
        servo.state = MotorState(position, 0.0, 0.5, 1.0, 12.0, 35.0)


def test_external_motion_model_owns_the_state() -> None:
    physics = SpringPhysics()
    servo = VirtualServo("XM430-W350", 1, motion=physics)
    write(servo, "drive_mode", 1)
    write(servo, "torque_enable", 1)
    write(servo, "goal_position", 2048 + 1000)
    servo.step(0.01)
    assert physics.seen[-1].goal_position_rad == pytest.approx(-1000 * PULSE)
    assert servo.peek("present_position") == 2048 + 500
    assert servo.peek("present_current") == round(-1.0 / 0.00269)


def test_external_motion_leaves_the_bridge_state_alone() -> None:
    servo = VirtualServo("XL430-W250", 1, motion=ExternalMotion())
    write(servo, "torque_enable", 1)
    write(servo, "goal_position", 3000)
    servo.state = MotorState(position_rad=0.25, velocity_rad_s=0.0, input_voltage_v=11.1)
    servo.step(1.0)
    assert servo.state.position_rad == 0.25
    assert servo.command().goal_position_rad == pytest.approx((3000 - 2048) * PULSE)


class WholeChainPhysics:
    """A stand-in for the twin bridge: one step for every servo on the bus."""

    def __init__(self) -> None:
        self.calls: list[tuple[int, float]] = []

    def advance(self, servos: Sequence[VirtualServo], dt_s: float) -> None:
        self.calls.append((len(servos), dt_s))
        for servo in servos:
            goal = servo.command().goal_position_rad
            servo.state = MotorState(goal, 0.0, 0.0, 0.0, 11.1, 30.0)


def test_chain_physics_steps_all_servos_once_per_advance() -> None:
    physics = WholeChainPhysics()
    chain = make_chain_for_ids("XL430-W250", [1, 2, 3], 1_000_000, motion=ExternalMotion())
    chain.physics = physics
    for servo in chain.servos:
        write(servo, "goal_position", 1000 + servo.servo_id)
    chain.advance(0.004)
    assert physics.calls == [(3, 0.004)]
    assert [s.peek("present_position") for s in chain.servos] == [1001, 1002, 1003]
