"""What a servo's step checks, decoded once per change of its table, and the faults it finds.

`StepRules` holds Torque Enable, the Bus Watchdog period and the fault limits of one table
version; `faults` says which `Fault`s the motor state sets off now: input voltage outside the
limits, temperature above its limit, an overload (the stall torque held for OVERLOAD_AFTER_S; on
a Feetech servo its Overload Torque held for its Protection Time, wiki memory-sts.md) and, on a
Feetech STS, an overcurrent (Protection Current 28 exceeded for the Overcurrent Protection Time
38). Each firmware says which bits of its status byte or error register report a fault
(`fault_bits`): Dynamixel's Hardware Error Status and Feetech's status byte differ.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from enum import Flag, auto

from snakebot.emulation.memory import ControlTableMemory
from snakebot.emulation.motion import MotorState

OVERLOAD_AFTER_S = 1.0
"""How long a Dynamixel servo holds its stall torque before the overload bit (no register)."""


class Fault(Flag):
    """What a servo can find wrong with itself, whatever its firmware's bits for it."""

    INPUT_VOLTAGE = auto()
    OVERHEATING = auto()
    OVERLOAD = auto()
    OVERCURRENT = auto()
    ENCODER = auto()


def bits_of(found: Fault, bits: Mapping[Fault, int]) -> int:
    """The register bits that report `found`, by a firmware's table `bits` (a fault the
    firmware has no bit for reports nothing)."""
    return sum(bit for fault, bit in bits.items() if fault in found)


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
    overcurrent_a: float = math.inf
    overcurrent_after_s: float = 0.0


def step_rules(memory: ControlTableMemory) -> StepRules:
    """Decode the writable items a step checks."""
    get, has = memory.get, memory.has
    overload: dict[str, float] = {}
    if has("overload_torque") and has("protection_time"):
        overload = {
            "overload_effort": get("overload_torque") / 100.0,
            "overload_after_s": get("protection_time") * memory.by_key["protection_time"].scale,
        }
    if has("protection_current") and has("overcurrent_protection_time"):
        overload["overcurrent_a"] = get("protection_current") * (
            memory.by_key["protection_current"].scale
        )
        time_scale = memory.by_key["overcurrent_protection_time"].scale
        overload["overcurrent_after_s"] = get("overcurrent_protection_time") * time_scale
    return StepRules(
        torque_enabled=get("torque_enable") == 1,
        watchdog_s=get("bus_watchdog") * 0.02 if has("bus_watchdog") else 0.0,
        min_volts_x10=get("min_voltage_limit"),
        max_volts_x10=get("max_voltage_limit"),
        temperature_limit_c=get("temperature_limit"),
        **overload,
    )


def faults(
    state: MotorState, rules: StepRules, dt_s: float, overload_s: float, overcurrent_s: float = 0.0
) -> tuple[Fault, float, float]:
    """(faults found, seconds overloaded so far, seconds over the protection current so far)
    after `dt_s` more of `state`."""
    found = Fault(0)
    volts = state.input_voltage_v * 10.0
    if not rules.min_volts_x10 <= volts <= rules.max_volts_x10:
        found |= Fault.INPUT_VOLTAGE
    if state.temperature_c > rules.temperature_limit_c:
        found |= Fault.OVERHEATING
    overloaded = abs(state.effort) >= rules.overload_effort and state.effort != 0.0
    overload_s = overload_s + dt_s if overloaded else 0.0
    if overload_s > rules.overload_after_s:
        found |= Fault.OVERLOAD
    overcurrent_s = overcurrent_s + dt_s if abs(state.current_a) > rules.overcurrent_a else 0.0
    if overcurrent_s > rules.overcurrent_after_s:
        found |= Fault.OVERCURRENT
    return found, overload_s, overcurrent_s
