"""What a virtual servo is told (`ServoCommand`) and what it does (`MotorState`), in SI units.

A `MotionModel` turns commands into state each step. `ProfileMotion` is the built-in kinematic
model (the servo's velocity profile, no load); `ExternalMotion` leaves the state to an outside
physics model (the MuJoCo twin bridge), which writes `servo.state` and reads `servo.command()`.
Positions are joint angles in rad with 0 at the centre tick (2048), before Homing Offset and the
Drive Mode direction are applied.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from snakebot.emulation.virtual_servo import VirtualServo

STEP_S = 0.001


class OperatingMode:
    """Operating Mode (11) values of X-series servos."""

    CURRENT = 0
    VELOCITY = 1
    POSITION = 3
    EXTENDED_POSITION = 4
    CURRENT_BASED_POSITION = 5
    PWM = 16
    POSITION_MODES = (3, 4, 5)


@dataclass(frozen=True)
class MotorState:
    """The physical state of one servo output shaft (SI).

    `effort` is the load as a fraction of stall torque (-1..1); `current_a` the motor current.
    """

    position_rad: float = 0.0
    velocity_rad_s: float = 0.0
    effort: float = 0.0
    current_a: float = 0.0
    input_voltage_v: float = 12.0
    temperature_c: float = 30.0


@dataclass(frozen=True)
class ServoCommand:
    """What the control table asks of the motor now, converted to SI in the motor's frame.

    Profile limits are None for "unlimited" (register value 0); `max_velocity_rad_s` already folds
    in the Velocity Limit and the no-load speed. `position_gains` is the Position (P, I, D) Gain
    registers as they are (register units), for a physics model of the position loop (zeros
    on an AX, whose loop is its compliance registers: a physics model reads those itself).
    """

    torque_enabled: bool
    operating_mode: int
    goal_position_rad: float
    goal_velocity_rad_s: float
    goal_current_a: float
    goal_pwm: float
    max_velocity_rad_s: float
    max_acceleration_rad_s2: float | None
    no_load_speed_rad_s: float
    position_gains: tuple[int, int, int]


class MotionModel(Protocol):
    """Advances a servo's `state` by `dt_s` seconds from its `command()`."""

    def step(self, servo: VirtualServo, dt_s: float) -> None:
        """Update `servo.state` for `dt_s` seconds of motion."""


class ChainPhysics(Protocol):
    """Moves every servo of a chain at once: the hook for the MuJoCo twin bridge.

    It reads each servo's `command()` and writes each servo's `state`. `EmulatedChain.advance`
    calls it with whatever `dt_s` the transport produces (microseconds to seconds), so a bridge
    accumulates time up to its physics step.
    """

    def advance(self, servos: Sequence[VirtualServo], dt_s: float) -> None:
        """Let `dt_s` seconds of physics pass for `servos`."""


class ExternalMotion:
    """The state belongs to an outside physics model that writes `servo.state`; no stepping."""

    def step(self, servo: VirtualServo, dt_s: float) -> None:
        """Leave the state as the physics bridge last wrote it."""


def _toward(velocity: float, target: float, max_change: float) -> float:
    return velocity + max(-max_change, min(max_change, target - velocity))


class ProfileMotion:
    """Kinematic servo: follows the goal along the velocity/acceleration profile, without load.

    Sub-steps of at most `step_s`; the reported effort is a small viscous load so Present Load and
    Present Current move with speed. In current-based position control (Operating Mode 5) Goal
    Current caps that load's current, so it caps the speed too.
    """

    def __init__(self, *, step_s: float = STEP_S, viscous_effort: float = 0.1) -> None:
        self.step_s = step_s
        self.viscous_effort = viscous_effort

    def step(self, servo: VirtualServo, dt_s: float) -> None:
        """Advance the servo's state by `dt_s` seconds."""
        state = servo.state
        command = servo.command()
        if not command.torque_enabled and state.velocity_rad_s == 0.0 and state.effort == 0.0:
            return
        position, velocity = state.position_rad, state.velocity_rad_s
        holding = command.operating_mode in OperatingMode.POSITION_MODES
        if holding and velocity == 0.0 and position == command.goal_position_rad:
            return
        remaining = dt_s
        stall_a = servo.table.specs.stall_current_a
        while remaining > 1e-12:
            h = min(self.step_s, remaining)
            remaining -= h
            target = self._target_velocity(command, position, velocity, h, stall_a)
            accel = command.max_acceleration_rad_s2
            velocity = target if accel is None else _toward(velocity, target, accel * h)
            position += velocity * h
        if holding and abs(command.goal_position_rad - position) < 1e-9 and abs(velocity) < 1e-9:
            position, velocity = command.goal_position_rad, 0.0
        no_load = max(command.no_load_speed_rad_s, 1e-9)
        effort = self.viscous_effort * velocity / no_load
        current = effort * servo.table.specs.stall_current_a
        servo.state = MotorState(
            position, velocity, effort, current, state.input_voltage_v, state.temperature_c
        )

    def _target_velocity(
        self, command: ServoCommand, position: float, velocity: float, h: float, stall_a: float
    ) -> float:
        if not command.torque_enabled:
            return 0.0
        v_max = command.max_velocity_rad_s
        mode = command.operating_mode
        if mode in OperatingMode.POSITION_MODES:
            if mode == OperatingMode.CURRENT_BASED_POSITION and self.viscous_effort * stall_a > 0:
                # Goal Current caps the drive: no faster than that current turns the load.
                fraction = abs(command.goal_current_a) / stall_a
                v_max = min(v_max, fraction / self.viscous_effort * command.no_load_speed_rad_s)
            error = command.goal_position_rad - position
            accel = command.max_acceleration_rad_s2
            if accel is not None:
                v_max = min(v_max, math.sqrt(2.0 * accel * abs(error)))
            return max(-v_max, min(v_max, error / h))
        if mode == OperatingMode.VELOCITY:
            return max(-v_max, min(v_max, command.goal_velocity_rad_s))
        if mode == OperatingMode.PWM:
            return command.goal_pwm * command.no_load_speed_rad_s
        if mode == OperatingMode.CURRENT:
            return math.copysign(v_max, command.goal_current_a) if command.goal_current_a else 0.0
        return velocity
