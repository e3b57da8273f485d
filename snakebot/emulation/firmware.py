"""The firmware's register semantics: write rules, the SI motor command, and present values.

Frames: the motor state is a joint angle with 0 rad at the centre tick (snakebot.servo.ticks: 2048
of 4096); the registers add the Drive Mode direction (bit 0 reverses position, velocity, load and
current) and the Homing Offset (Present Position = actual + offset, not flipped by the direction;
e-Manual homing offset).
"""

from __future__ import annotations

import math
from enum import IntFlag
from typing import TYPE_CHECKING

from snakebot.emulation.alarms import Fault, bits_of
from snakebot.emulation.memory import ControlTableMemory, WritePlan
from snakebot.emulation.motion import MotorState, OperatingMode, ServoCommand
from snakebot.emulation.protocol import StatusError
from snakebot.servo.ticks import centre_tick

if TYPE_CHECKING:
    from snakebot.emulation.virtual_servo import VirtualServo

GOALS = ("goal_pwm", "goal_current", "goal_velocity", "goal_position")
_MODE_RESETS = (
    "velocity_i_gain",
    "velocity_p_gain",
    "position_d_gain",
    "position_i_gain",
    "position_p_gain",
    "profile_acceleration",
    "profile_velocity",
)


class HardwareError(IntFlag):
    """Hardware Error Status(70) / Shutdown(63) bits of X-series servos (e-Manual shutdown page)."""

    INPUT_VOLTAGE = 0x01
    OVERHEATING = 0x04
    MOTOR_ENCODER = 0x08
    ELECTRICAL_SHOCK = 0x10
    OVERLOAD = 0x20


FAULT_BITS = {
    Fault.INPUT_VOLTAGE: HardwareError.INPUT_VOLTAGE,
    Fault.OVERHEATING: HardwareError.OVERHEATING,
    Fault.ENCODER: HardwareError.MOTOR_ENCODER,
    Fault.OVERLOAD: HardwareError.OVERLOAD,
}
"""The Hardware Error Status bit of each fault (Protocol 1.0's status byte shares the voltage,
overheating and overload bits: `VirtualServo.alarm_bits`)."""


def fault_bits(found: Fault) -> int:
    """The Hardware Error Status bits that report `found`."""
    return bits_of(found, FAULT_BITS)


def wrap_turn(position_rad: float) -> float:
    """Fold a multi-turn angle into one turn around the centre tick, as a reboot does."""
    return (position_rad + math.pi) % (2.0 * math.pi) - math.pi


def pwm_full_scale(memory: ControlTableMemory) -> int:
    """Goal/Present PWM of 100 % duty: the PWM Limit register's maximum (885 on the X series)."""
    return memory.table["pwm_limit"].maximum


def direction(memory: ControlTableMemory) -> int:
    """+1, or -1 when Drive Mode bit 0 (reverse) is set."""
    return -1 if memory.get("drive_mode") & 0x01 else 1


def homing_offset(memory: ControlTableMemory) -> int:
    """The Homing Offset in effect, in ticks."""
    offset = memory.get("homing_offset")
    # Offsets beyond ±1024 are ignored in Position Control Mode (e-Manual homing offset).
    if memory.get("operating_mode") == OperatingMode.POSITION and abs(offset) > 1024:
        return 0
    return offset


def position_ticks(memory: ControlTableMemory, state: MotorState) -> int:
    """Present Position for a motor state."""
    pulse = memory.by_key["present_position"].scale
    ticks = round(direction(memory) * state.position_rad / pulse)
    return centre_tick(memory.table.specs.ticks) + ticks + homing_offset(memory)


def command(servo: VirtualServo) -> ServoCommand:
    """The control table's request in SI, in the motor's frame."""
    memory, specs = servo.memory, servo.table.specs
    get = memory.get

    def scale(key: str) -> float:
        return memory.by_key[key].scale

    sign, offset = direction(memory), homing_offset(memory)
    rpm, no_load = scale("goal_velocity"), specs.no_load_speed_rad_s
    mode = get("operating_mode")
    time_based = bool(get("drive_mode") & 0x04)
    max_velocity = min(no_load, get("velocity_limit") * rpm or no_load)
    profile = get("profile_velocity") * rpm
    if mode in OperatingMode.POSITION_MODES and profile > 0 and not time_based:
        max_velocity = min(max_velocity, profile)
    acceleration = get("profile_acceleration") * scale("profile_acceleration")
    current = get("goal_current") * scale("goal_current") if memory.has("goal_current") else 0.0
    return ServoCommand(
        torque_enabled=get("torque_enable") == 1,
        operating_mode=mode,
        goal_position_rad=sign
        * (get("goal_position") - offset - centre_tick(specs.ticks))
        * scale("goal_position"),
        goal_velocity_rad_s=sign * get("goal_velocity") * rpm,
        goal_current_a=sign * current,
        goal_pwm=sign * get("goal_pwm") / pwm_full_scale(memory),
        max_velocity_rad_s=max_velocity,
        max_acceleration_rad_s2=acceleration if acceleration > 0 and not time_based else None,
        no_load_speed_rad_s=no_load,
        position_gains=(get("position_p_gain"), get("position_i_gain"), get("position_d_gain")),
    )


def check_write(servo: VirtualServo, plan: WritePlan) -> int:
    """Firmware rules beyond the static item range; returns an error number or 0."""
    values, memory = plan.values, servo.memory
    get, specs = memory.get, servo.table.specs

    def new(key: str) -> int:
        return values[key] if key in values else get(key)

    if servo.torque_enabled and any(r.eeprom for r in plan.items):
        return StatusError.ACCESS
    if "operating_mode" in values and values["operating_mode"] not in specs.operating_modes:
        return StatusError.DATA_RANGE
    if "baud_rate" in values and values["baud_rate"] not in specs.baud_rates:
        return StatusError.DATA_RANGE
    if servo.watchdog_tripped and (
        any(k in values for k in GOALS) or values.get("bus_watchdog", 0) != 0
    ):
        return StatusError.DATA_RANGE
    if values.get("torque_enable") == 1 and get("hardware_error_status") & get("shutdown"):
        return StatusError.RESULT_FAIL
    limits = [("goal_velocity", "velocity_limit"), ("goal_pwm", "pwm_limit")]
    limits += [("goal_current", "current_limit")] if memory.has("current_limit") else []
    for goal, limit in limits:
        if goal in values and abs(values[goal]) > new(limit):
            return StatusError.DATA_LIMIT
    if "goal_position" in values and new("operating_mode") == OperatingMode.POSITION:
        low, high = new("min_position_limit"), new("max_position_limit")
        if not low <= values["goal_position"] <= high:
            return StatusError.DATA_LIMIT
    return 0


def apply_side_effects(servo: VirtualServo, values: dict[str, int]) -> None:
    """What a successful write sets off besides storing its bytes."""
    memory = servo.memory
    if "operating_mode" in values:
        # A mode change resets gains and profiles and loses the turn count (e-Manual opmode).
        for key in _MODE_RESETS:
            memory.set(key, memory.by_key[key].default)
        reset_goal_limits(memory)
        servo.state = _with_position(servo.state, wrap_turn(servo.state.position_rad))
    goal_update = any(k in values for k in GOALS)
    if goal_update and memory.get("drive_mode") & 0x08 and not servo.torque_enabled:
        memory.set("torque_enable", 1)


def reset_goal_limits(memory: ControlTableMemory) -> None:
    """Goal PWM and Goal Current back to their limits, as at boot and on a mode change."""
    memory.set("goal_pwm", memory.get("pwm_limit"))
    if memory.has("goal_current") and memory.has("current_limit"):
        memory.set("goal_current", memory.get("current_limit"))


def _with_position(state: MotorState, position_rad: float) -> MotorState:
    return MotorState(
        position_rad,
        state.velocity_rad_s,
        state.effort,
        state.current_a,
        state.input_voltage_v,
        state.temperature_c,
    )


def refresh_present(servo: VirtualServo) -> None:
    """Write the present values (from the SI motor state) into the control table."""
    memory, state, sign = servo.memory, servo.state, direction(servo.memory)
    velocity = round(sign * state.velocity_rad_s / memory.by_key["present_velocity"].scale)
    position = position_ticks(memory, state)
    memory.set("present_position", position)
    memory.set("position_trajectory", position)
    memory.set("present_velocity", velocity)
    memory.set("velocity_trajectory", velocity)
    if memory.has("present_load"):
        memory.set("present_load", round(max(-1.0, min(1.0, sign * state.effort)) * 1000))
    if memory.has("present_current"):
        scale = memory.by_key["present_current"].scale
        memory.set("present_current", round(sign * state.current_a / scale))
    no_load = max(servo.table.specs.no_load_speed_rad_s, 1e-9)
    pwm = max(-1.0, min(1.0, state.velocity_rad_s / no_load + state.effort))
    full = pwm_full_scale(memory)
    memory.set("present_pwm", round(sign * pwm * full) if servo.torque_enabled else 0)
    memory.set("present_input_voltage", round(state.input_voltage_v * 10.0))
    memory.set("present_temperature", round(state.temperature_c))
    moving = abs(velocity) > memory.get("moving_threshold")
    memory.set("moving", int(moving))
    in_position = abs(memory.get("goal_position") - position) <= 2
    memory.set("moving_status", int(in_position) | (0x02 if moving else 0))
    memory.set("realtime_tick", int(servo.uptime_s * 1000.0) % 32768)
