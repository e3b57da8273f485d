"""The firmware of Feetech control tables (STS/SMS magnetic, SCS potentiometer): write rules, the
SI motor command and present values, in the same functions as `firmware` (Dynamixel X series).

Rules (Feetech wiki docs/en/reference/parameter/memory-sts.md, memory-scscl.md; lerobot
motors/feetech; servo-families.md §2):

- Lock (55 on an STS, 48 on an SCS): "write 0 ... values written to EEPROM addresses persist
  after power-off; write 1 ... values written to EEPROM addresses do not persist". A write to
  EEPROM always takes effect at once; only a write made while Lock reads 0 is saved, and a
  restart (0x08) or power cycle brings back the saved image (`VirtualServo.saved_eeprom`, what
  the emulator's state file keeps).
- Position offset (31, sign bit 11): Present Position = Actual - Offset (lerobot), Goal Position
  in the same frame. Torque Enable 128 makes the present position the tick centre (2048) by
  setting the offset (and saves it, as the calibration instruction does), then leaves the
  torque off.
- Positions and speeds are sign-magnitude (bit 15), Present Load bit 10; words are little-endian
  on an STS and big-endian on an SCS (END (2); `memory.byte_order`).
- A Goal Position beyond the angle limits is held at the nearer limit (no error bit exists to
  refuse it); both limits 0 selects multi-turn on an STS, motor (PWM) mode on an SCS.
- Operating Mode (33, STS): 0 position, 1 constant speed (Goal Speed signed), 2 PWM (Goal Time,
  bit 10 the direction, 0.1 %), 3 step (served as position).
- Goal Speed 0 in position mode is the fastest the servo goes; Acceleration 0 is no limit.
- Torque Limit (48) starts at Max Torque (16) on power-up; Torque Enable 2 (damping) drives no
  position. Torque Enable 1 clears the status bits (their cause is checked again next step).
- A Goal Position write turns the torque on when it is off: Feetech's own example programs
  (FTServo_Python sms_sts/write.py, scscl/reg_write.py) move a servo fresh from power-up without
  ever writing Torque Enable.
"""

from __future__ import annotations

import math
from enum import IntFlag
from typing import TYPE_CHECKING

from snakebot.emulation.alarms import Fault, bits_of
from snakebot.emulation.memory import ControlTableMemory, WritePlan
from snakebot.emulation.motion import MotorState, OperatingMode, ServoCommand
from snakebot.emulation.protocol import StatusError
from snakebot.servo_tables.table import decode_magnitude

if TYPE_CHECKING:
    from snakebot.emulation.virtual_servo import VirtualServo


class StatusBit(IntFlag):
    """The status byte's error bits, also Servo Status (65), Unload Condition (19) and LED
    Alarm (20): FTServo_Python's ERRBIT_VOLTAGE, ERRBIT_ANGLE, ERRBIT_OVERHEAT, ERRBIT_OVERELE
    and ERRBIT_OVERLOAD (servo-families.md §1.3). Not Dynamixel's: 2 is the angle sensor, 8
    the current."""

    VOLTAGE = 0x01
    ANGLE = 0x02
    OVERHEAT = 0x04
    OVERCURRENT = 0x08
    OVERLOAD = 0x20


FAULT_BITS = {
    Fault.INPUT_VOLTAGE: StatusBit.VOLTAGE,
    Fault.ENCODER: StatusBit.ANGLE,
    Fault.OVERHEATING: StatusBit.OVERHEAT,
    Fault.OVERCURRENT: StatusBit.OVERCURRENT,
    Fault.OVERLOAD: StatusBit.OVERLOAD,
}


def fault_bits(found: Fault) -> int:
    """The status bits that report `found`."""
    return bits_of(found, FAULT_BITS)


PWM_SIGN_BIT = 10
"""Goal Time's direction bit in motor (PWM) mode (wiki memory-sts.md, memory-scscl.md)."""
CALIBRATE = 128
"""Torque Enable value that makes the present position the middle (the model's tick centre)."""
TORQUE_VALUES = (0, 1, 2, CALIBRATE)
PID_KEYS = ("position_p_gain", "position_i_gain", "position_d_gain")
SPEED_KEYS = ("goal_speed", "moving_speed")
VOLTAGE_KEYS = ("present_input_voltage", "present_voltage")
_FEETECH_MODES = {0: OperatingMode.POSITION, 1: OperatingMode.VELOCITY, 2: OperatingMode.PWM}


def _first(memory: ControlTableMemory, keys: tuple[str, ...]) -> str | None:
    return next((key for key in keys if memory.has(key)), None)


def offset(memory: ControlTableMemory) -> int:
    """The Position offset in ticks (0 on a model without one)."""
    return memory.get("homing_offset") if memory.has("homing_offset") else 0


def _limits_zero(memory: ControlTableMemory) -> bool:
    return memory.get("min_position_limit") == 0 == memory.get("max_position_limit")


def mode(memory: ControlTableMemory) -> int:
    """The `OperatingMode` the table selects."""
    if memory.has("operating_mode"):
        return _FEETECH_MODES.get(memory.get("operating_mode"), OperatingMode.POSITION)
    return OperatingMode.PWM if _limits_zero(memory) else OperatingMode.POSITION


def actual_ticks(memory: ControlTableMemory, state: MotorState) -> int:
    """The encoder's reading for a motor state (before the offset)."""
    ticks = memory.table.specs.ticks
    return ticks.centre + round(state.position_rad * ticks.ticks_per_rad)


def position_ticks(memory: ControlTableMemory, state: MotorState) -> int:
    """Present Position for a motor state: Actual - Offset."""
    return actual_ticks(memory, state) - offset(memory)


def goal_frame(memory: ControlTableMemory) -> tuple[int, int, int, float, float, float]:
    """`command`'s Goal Position decode as (direction, offset, centre, rad per tick, low, high):
    goal_rad = direction * (clamp(goal, low, high) - offset - centre) * rad per tick, the same
    expression, so a write of Goal Position alone needs no full decode (`VirtualServo`)."""
    ticks = memory.table.specs.ticks
    low, high = -math.inf, math.inf
    if not _limits_zero(memory):
        low, high = memory.get("min_position_limit"), memory.get("max_position_limit")
    return 1, -offset(memory), ticks.centre, ticks.rad_per_tick, low, high


def command(servo: VirtualServo) -> ServoCommand:
    """The control table's request in SI."""
    memory, specs = servo.memory, servo.table.specs
    get = memory.get
    no_load = specs.no_load_speed_rad_s
    speed_key = _first(memory, SPEED_KEYS)
    speed = get(speed_key) if speed_key else 0
    rad_s = memory.by_key[speed_key].scale if speed_key else 0.0
    selected = mode(memory)
    sign, off, centre, rad_per_tick, low, high = goal_frame(memory)
    goal = max(low, min(high, get("goal_position")))
    acceleration = 0.0
    if memory.has("acceleration"):
        acceleration = get("acceleration") * memory.by_key["acceleration"].scale
    pwm = 0.0
    if selected == OperatingMode.PWM and memory.has("goal_time"):
        duty = get("goal_time")
        if memory.by_key["goal_time"].sign_bit is None:  # an SCS's time in ms, bit 10 in PWM
            duty = decode_magnitude(duty, PWM_SIGN_BIT)
        pwm = duty / 1000.0
    gains = tuple(get(k) if memory.has(k) else 0 for k in PID_KEYS)
    limited = memory.has("torque_limit") and get("torque_limit") == 0
    return ServoCommand(
        torque_enabled=get("torque_enable") == 1 and not limited,
        operating_mode=selected,
        goal_position_rad=sign * (goal - off - centre) * rad_per_tick,
        goal_velocity_rad_s=speed * rad_s,
        goal_current_a=0.0,
        goal_pwm=max(-1.0, min(1.0, pwm)),
        max_velocity_rad_s=min(no_load, abs(speed) * rad_s or no_load),
        max_acceleration_rad_s2=acceleration if acceleration > 0 else None,
        no_load_speed_rad_s=no_load,
        position_gains=(gains[0], gains[1], gains[2]),
    )


def check_write(servo: VirtualServo, plan: WritePlan) -> int:
    """Firmware rules beyond the static item range; an error number (the write is dropped: a
    Feetech status byte has no bit to say so) or 0."""
    values, specs = plan.values, servo.table.specs
    if "torque_enable" in values and values["torque_enable"] not in TORQUE_VALUES:
        return StatusError.DATA_RANGE
    if "baud_rate" in values and values["baud_rate"] not in specs.baud_rates:
        return StatusError.DATA_RANGE
    if "operating_mode" in values and values["operating_mode"] not in specs.operating_modes:
        return StatusError.DATA_RANGE
    return 0


def calibrate_middle(servo: VirtualServo, present: int | None = None) -> None:
    """Make the present position read `present` (by default the model's tick centre, 2048 on
    an STS) by setting the Position offset, and save it (torque 128 and the calibration
    instruction OFSCAL)."""
    memory = servo.memory
    if not memory.has("homing_offset"):
        return
    if present is None:
        present = memory.table.specs.ticks.centre
    register = memory.by_key["homing_offset"]
    wanted = actual_ticks(memory, servo.state) - present
    memory.set("homing_offset", max(register.minimum, min(register.maximum, wanted)))
    servo.save_eeprom()


def apply_side_effects(servo: VirtualServo, values: dict[str, int]) -> None:
    """Torque 128 calibrates, Torque 1 clears the status bits, and an EEPROM write made while
    Lock reads 0 is saved."""
    memory = servo.memory
    torque = values.get("torque_enable")
    if torque == CALIBRATE:
        calibrate_middle(servo)
        memory.set("torque_enable", 0)
    elif torque == 1:
        servo.clear_alarms()
    elif torque is None and "goal_position" in values and memory.get("torque_enable") == 0:
        memory.set("torque_enable", 1)
    eeprom = any(memory.by_key[key].eeprom for key in values)
    if eeprom and memory.has("lock") and memory.get("lock") == 0:
        servo.save_eeprom()


def reset_goal_limits(memory: ControlTableMemory) -> None:
    """Torque Limit = Max Torque, as at power-up."""
    if memory.has("max_torque") and memory.has("torque_limit"):
        memory.set("torque_limit", memory.get("max_torque"))


def refresh_present(servo: VirtualServo) -> None:
    """Write the present values (from the SI motor state) into the control table."""
    memory, state = servo.memory, servo.state
    present = memory.by_key["present_position"]
    position = max(present.minimum, min(present.maximum, position_ticks(memory, state)))
    memory.set("present_position", position)
    speed = memory.by_key["present_velocity"]
    velocity = round(state.velocity_rad_s / speed.scale) if speed.scale else 0
    memory.set("present_velocity", velocity)
    load = round(max(-1.0, min(1.0, state.effort)) * 1000)
    memory.set("present_load", load if servo.torque_enabled else 0)
    if memory.has("present_current"):
        scale = memory.by_key["present_current"].scale
        memory.set("present_current", round(state.current_a / scale))
    voltage = _first(memory, VOLTAGE_KEYS)
    if voltage is not None:
        memory.set(voltage, round(state.input_voltage_v * 10.0))
    memory.set("present_temperature", round(state.temperature_c))
    memory.set("moving", int(velocity != 0))
    if memory.has("status"):
        memory.set("status", int(servo.hardware_error))
    if memory.has("present_goal_position"):
        memory.set("present_goal_position", memory.get("goal_position"))
