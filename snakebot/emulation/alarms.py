"""What a servo's step checks, decoded once per change of its table, and the faults it finds.

`StepRules` holds Torque Enable, the Bus Watchdog period and the fault limits of one table
version; `faults` says which hardware error bits the motor state sets off now: input voltage
outside the limits, temperature above its limit, and an overload (the stall torque held for
OVERLOAD_AFTER_S; on a Feetech servo its Overload Torque held for its Protection Time, wiki
memory-sts.md).
"""

from __future__ import annotations

from dataclasses import dataclass

from snakebot.emulation.firmware import HardwareError
from snakebot.emulation.memory import ControlTableMemory
from snakebot.emulation.motion import MotorState

OVERLOAD_AFTER_S = 1.0
"""How long a Dynamixel servo holds its stall torque before the overload bit (no register)."""


@dataclass(frozen=True)
class StepRules:
    """Torque Enable, Bus Watchdog (s) and the fault limits, as of one table version."""

    torque_enabled: bool
    watchdog_s: float
    min_volts_x10: int
    max_volts_x10: int
    temperature_limit_c: int
    overload_effort: float = 1.0
    overload_after_s: float = OVERLOAD_AFTER_S


def step_rules(memory: ControlTableMemory) -> StepRules:
    """Decode the writable items a step checks."""
    get, has = memory.get, memory.has
    overload: dict[str, float] = {}
    if has("overload_torque") and has("protection_time"):
        overload = {
            "overload_effort": get("overload_torque") / 100.0,
            "overload_after_s": get("protection_time") * memory.by_key["protection_time"].scale,
        }
    return StepRules(
        torque_enabled=get("torque_enable") == 1,
        watchdog_s=get("bus_watchdog") * 0.02 if has("bus_watchdog") else 0.0,
        min_volts_x10=get("min_voltage_limit"),
        max_volts_x10=get("max_voltage_limit"),
        temperature_limit_c=get("temperature_limit"),
        **overload,
    )


def faults(
    state: MotorState, rules: StepRules, dt_s: float, overload_s: float
) -> tuple[int, float]:
    """(hardware error bits found, seconds overloaded so far) after `dt_s` more of `state`."""
    found = 0
    volts = state.input_voltage_v * 10.0
    if not rules.min_volts_x10 <= volts <= rules.max_volts_x10:
        found |= HardwareError.INPUT_VOLTAGE
    if state.temperature_c > rules.temperature_limit_c:
        found |= HardwareError.OVERHEATING
    overloaded = abs(state.effort) >= rules.overload_effort and state.effort != 0.0
    overload_s = overload_s + dt_s if overloaded else 0.0
    if overload_s > rules.overload_after_s:
        found |= HardwareError.OVERLOAD
    return found, overload_s
