"""The firmware of Protocol 1.0 control tables (AX-12A/18A, MX with 1.0 firmware): write rules,
the SI motor command and present values, in the same functions as `firmware` (X series).

These tables have no Operating Mode, Drive Mode or Homing Offset: the CW/CCW Angle Limits choose
joint mode (a Goal Position outside them is refused: the Angle Limit bit, no move) or wheel mode
(both 0: Moving Speed turns the output, bit 10 the direction). Moving Speed is the speed limit
in joint mode (0 = as fast as it goes). Torque Limit (34) starts at Max Torque (14) on power-up;
0 leaves the output free. Lock (47) = 1 refuses EEPROM writes until the next power cycle, and 0
cannot be written back. EEPROM is writable with torque on (unlike the X series). The position
loop is the MX's P/I/D registers (`ServoCommand.position_gains`) or the AX's Compliance
registers, which a physics model reads from the table. References: e-Manual ax-12a.md, mx-28.md
(control tables); servo-families.md §3.2.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from snakebot.emulation import firmware
from snakebot.emulation.alarms import Fault
from snakebot.emulation.memory import ControlTableMemory, WritePlan
from snakebot.emulation.motion import MotorState, OperatingMode, ServoCommand
from snakebot.emulation.protocol import StatusError

if TYPE_CHECKING:
    from snakebot.emulation.virtual_servo import VirtualServo

GOALS = ("goal_position", "moving_speed")
PID_KEYS = ("position_p_gain", "position_i_gain", "position_d_gain")
MULTI_TURN_LIMIT = 4095
"""Both angle limits at 4095 select multi-turn mode on an MX (e-Manual mx-28.md)."""


def fault_bits(found: Fault) -> int:
    """The X series' bits: the emulator keeps a Protocol 1.0 servo's alarms in the same ones
    (its status byte shares the voltage, overheating and overload bits)."""
    return firmware.fault_bits(found)


def wheel_mode(memory: ControlTableMemory) -> bool:
    """Whether both angle limits are 0 (wheel mode: endless turning at Moving Speed)."""
    return memory.get("min_position_limit") == 0 == memory.get("max_position_limit")


def multi_turn(memory: ControlTableMemory, limits: tuple[int, int] | None = None) -> bool:
    """Whether both angle limits are 4095 (MX multi-turn mode)."""
    low, high = limits or (memory.get("min_position_limit"), memory.get("max_position_limit"))
    return memory.has("multi_turn_offset") and low == high == MULTI_TURN_LIMIT


def position_ticks(memory: ControlTableMemory, state: MotorState) -> int:
    """Present Position for a motor state (no direction or offset registers to apply)."""
    ticks = memory.table.specs.ticks
    return ticks.to_ticks(state.position_rad)


def command(servo: VirtualServo) -> ServoCommand:
    """The control table's request in SI."""
    memory, specs = servo.memory, servo.table.specs
    get = memory.get
    rad_s = memory.by_key["moving_speed"].scale
    no_load = specs.no_load_speed_rad_s
    speed = get("moving_speed")
    wheel = wheel_mode(memory)
    # Joint mode: 0 = no speed control (the fastest it goes). Wheel mode: bit 10 set = CW
    # (towards the CW Angle Limit, falling ticks), which the register decodes as negative.
    max_velocity = min(no_load, abs(speed) * rad_s or no_load)
    acceleration = 0.0
    if memory.has("goal_acceleration"):
        acceleration = get("goal_acceleration") * memory.by_key["goal_acceleration"].scale
    p_i_d = tuple(get(k) if memory.has(k) else 0 for k in PID_KEYS)
    return ServoCommand(
        torque_enabled=get("torque_enable") == 1 and get("torque_limit") > 0,
        operating_mode=OperatingMode.VELOCITY if wheel else OperatingMode.POSITION,
        goal_position_rad=specs.ticks.to_rad(get("goal_position")),
        goal_velocity_rad_s=speed * rad_s if wheel else 0.0,
        goal_current_a=0.0,
        goal_pwm=0.0,
        max_velocity_rad_s=no_load if wheel else max_velocity,
        max_acceleration_rad_s2=acceleration if acceleration > 0 else None,
        no_load_speed_rad_s=no_load,
        position_gains=(p_i_d[0], p_i_d[1], p_i_d[2]),
    )


def check_write(servo: VirtualServo, plan: WritePlan) -> int:
    """Firmware rules beyond the static item range; returns a Protocol 2.0 error number or 0
    (the Protocol 1.0 side turns it into a bit)."""
    values, memory = plan.values, servo.memory
    get = memory.get

    def new(key: str) -> int:
        return values[key] if key in values else get(key)

    locked = memory.has("lock") and get("lock") == 1
    if locked and (any(r.eeprom for r in plan.items) or values.get("lock") == 0):
        return StatusError.DATA_RANGE
    if "baud_rate" in values and values["baud_rate"] not in servo.table.specs.baud_rates:
        return StatusError.DATA_RANGE
    limits = (new("min_position_limit"), new("max_position_limit"))
    wheel = limits[0] == 0 == limits[1]
    if "moving_speed" in values and not wheel and values["moving_speed"] < 0:
        return StatusError.DATA_RANGE  # bit 10 is a direction in wheel mode only
    goal = values.get("goal_position")
    joint = not wheel and not multi_turn(memory, limits)
    if joint and goal is not None and not limits[0] <= goal <= limits[1]:
        return StatusError.DATA_LIMIT
    return 0


def apply_side_effects(servo: VirtualServo, values: dict[str, int]) -> None:
    """Torque Enable 1 clears the alarms (their cause is checked again on the next step)."""
    if values.get("torque_enable") == 1:
        servo.clear_alarms()


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
    velocity = round(state.velocity_rad_s / speed.scale)
    memory.set("present_velocity", max(-1023, min(1023, velocity)))
    load = round(max(-1.0, min(1.0, state.effort)) * 1023)
    memory.set("present_load", load if servo.torque_enabled else 0)
    memory.set("present_input_voltage", round(state.input_voltage_v * 10.0))
    memory.set("present_temperature", round(state.temperature_c))
    memory.set("moving", int(velocity != 0))
    if memory.has("realtime_tick"):
        memory.set("realtime_tick", int(servo.uptime_s * 1000.0) % 32768)
